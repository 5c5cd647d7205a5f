"""A connectome's node labels drawn over a rendered image, beside each labelled node's sphere.

The labels (:attr:`~brainpainter.connectome.model.Connectome.labelled`) are 2-D text drawn after the
3-D render: dark text with a light halo (it reads over the glass, the edges and the background), its
height a fixed share of the image's (:data:`TEXT_SHARE`). Labels are placed one after another (the
largest node value first, else the strongest node: :func:`~brainpainter.connectome.labels.ranked`), each
at the first of :data:`PLACES` around their sphere's projected rim (just right of it, else
left of it, else above or below) where the text lies inside the image and overlaps no label placed
before (:func:`place_labels`, a greedy placement); a label that fits nowhere, or whose node projects
outside the image, is left out (and logged).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.labels import ranked
from brainpainter.connectome.model import Connectome
from brainpainter.rendering import framing
from brainpainter.rendering.connectome_parts import node_radii

#: Text height as a share of the image's height (12 px at 400 px, 72 px at 2400 px).
TEXT_SHARE = 0.03
#: The smallest text height, pixels.
MIN_TEXT = 9
#: RGBA of the text and of its halo.
TEXT_RGBA = (20, 20, 20, 255)
HALO_RGBA = (255, 255, 255, 255)
#: Where a label is tried, in order: PIL's text anchor and the offset from the node's centre, in units of
#: the gap between the centre and the text (right, left, then above and below on either side, then
#: centred above and below).
PLACES = (("lm", 1, 0), ("rm", -1, 0), ("ls", 1, -1), ("la", 1, 1), ("rs", -1, -1), ("ra", -1, 1),
          ("ms", 0, -1), ("ma", 0, 1))

#: A label's box on the image: left, top, right, bottom (pixels; the text with its halo).
Box = tuple[float, float, float, float]
#: A label drawn: its node, and the point and PIL anchor its text is drawn at.
Placed = tuple[int, tuple[float, float], str]
_log = logging.getLogger(__name__)


def text_height(image_height: int, share: float | None = None) -> int:
    """The labels' font size in pixels for an image `image_height` pixels tall (`share` of it, default
    :data:`TEXT_SHARE`; a figure's: :attr:`~brainpainter.connectome.model.Connectome.label_share`)."""
    return max(MIN_TEXT, round((TEXT_SHARE if share is None else share) * image_height))


def draw_node_labels(pixels: NDArray[Any], connectome: Connectome, pose: framing.CameraPose) -> NDArray[Any]:
    """`pixels` with the labels of `connectome`'s labelled nodes drawn on (a new array).

    Parameters
    ----------
    pixels : ndarray of uint8, shape (h, w, 4) or (h, w, 3)
        The rendered image.
    connectome : Connectome
        Its ``labelled`` nodes are labelled with :meth:`~Connectome.label_texts`.
    pose : CameraPose
        The camera `pixels` was rendered with (:meth:`SceneGeometry.camera`).

    Returns
    -------
    ndarray of uint8, the shape of `pixels`
    """
    if not connectome.labelled:
        return pixels
    from PIL import Image, ImageDraw, ImageFont

    height, width = pixels.shape[:2]
    index = ranked(connectome, np.asarray(connectome.labelled, dtype=np.intp))  # the first placed first
    centre = framing.to_pixels(connectome.positions[index], pose, width, height)
    rim = framing.to_pixels(connectome.positions[index] + pose.right * node_radii(
        connectome.node_values, connectome.n_nodes)[index, None], pose, width, height)
    size = text_height(height, connectome.label_share)
    font = ImageFont.load_default(size=size)
    image = Image.fromarray(np.ascontiguousarray(pixels))
    draw = ImageDraw.Draw(image)
    texts = connectome.label_texts()
    halo = max(1, size // 8)
    channels = len(image.getbands())
    fill, stroke = TEXT_RGBA[:channels], HALO_RGBA[:channels]
    gaps = np.abs(rim[:, 0] - centre[:, 0]) + halo + size * 0.2

    def box(i: int, xy: tuple[float, float], anchor: str) -> Box:
        left, top, right, bottom = draw.textbbox(xy, texts[i], font=font, anchor=anchor, stroke_width=halo)
        return float(left), float(top), float(right), float(bottom)

    placed, left_out = place_labels([int(i) for i in index], centre, gaps, (width, height), box)
    for i, xy, anchor in placed:
        draw.text(xy, texts[i], font=font, fill=fill, anchor=anchor, stroke_width=halo, stroke_fill=stroke)
    if left_out:
        _log.info("node labels left out (their node is outside the image, or they fit nowhere without "
                  "overlapping another label): %s", ", ".join(texts[i] for i in left_out))
    return np.asarray(image)


def place_labels(nodes: list[int], centres: NDArray[Any], gaps: NDArray[Any], size: tuple[int, int],
                 box: Callable[[int, tuple[float, float], str], Box]) -> tuple[list[Placed], list[int]]:
    """A greedy placement of labels that do not overlap: each at the first of :data:`PLACES` that fits.

    Parameters
    ----------
    nodes : list of int
        The labelled nodes, in the order they are placed.
    centres : ndarray, shape (n, 2)
        Their projected centres (column, row), pixels.
    gaps : ndarray, shape (n,)
        Distance from each centre to its text (the sphere's projected radius and a margin), pixels.
    size : (int, int)
        The image's width and height.
    box : callable
        ``box(node, (x, y), anchor)``: the :data:`Box` its text would cover.

    Returns
    -------
    placed : list of :data:`Placed`
        Each label drawn: its node, the point and the PIL anchor to draw its text at.
    left_out : list of int
        The nodes whose label is not drawn: outside the image, or overlapping wherever it goes.
    """
    width, height = size
    taken: list[Box] = []
    placed: list[Placed] = []
    left_out: list[int] = []
    for i, (x, y), gap in zip(nodes, centres, gaps, strict=True):
        if not (0.0 <= x < width and 0.0 <= y < height):
            left_out.append(i)
            continue
        for anchor, dx, dy in PLACES:
            xy = (float(x + dx * gap), float(y + dy * gap))
            b = box(i, xy, anchor)
            inside = b[0] >= 0 and b[1] >= 0 and b[2] <= width and b[3] <= height
            if inside and not any(_overlap(b, t) for t in taken):
                taken.append(b)
                placed.append((i, xy, anchor))
                break
        else:
            left_out.append(i)
    return placed, left_out


def _overlap(a: Box, b: Box) -> bool:
    """Whether boxes `a` and `b` share any pixel."""
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
