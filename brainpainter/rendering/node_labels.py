"""A connectome's node labels drawn over a rendered image, beside each labelled node's sphere.

The labels (:attr:`~brainpainter.connectome.model.Connectome.labelled`) are 2-D text drawn after the
3-D render: dark text with a light halo (it reads over the glass, the edges and the background), its
height a fixed share of the image's (:data:`TEXT_SHARE`), left-aligned just right of the sphere's
projected rim (right-aligned left of it where it would run off the image's right edge). A label
whose node projects outside the image is left out.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

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


def text_height(image_height: int) -> int:
    """The labels' font size in pixels for an image `image_height` pixels tall."""
    return max(MIN_TEXT, round(TEXT_SHARE * image_height))


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
    index = np.asarray(connectome.labelled, dtype=np.intp)
    centre = framing.to_pixels(connectome.positions[index], pose, width, height)
    rim = framing.to_pixels(connectome.positions[index] + pose.right * node_radii(
        connectome.node_values, connectome.n_nodes)[index, None], pose, width, height)
    size = text_height(height)
    font = ImageFont.load_default(size=size)
    image = Image.fromarray(np.ascontiguousarray(pixels))
    draw = ImageDraw.Draw(image)
    texts = connectome.label_texts()
    halo = max(1, size // 8)
    channels = len(image.getbands())
    fill, stroke = TEXT_RGBA[:channels], HALO_RGBA[:channels]
    for i, (x, y), (rx, _) in zip(index, centre, rim, strict=True):
        if not (0.0 <= x < width and 0.0 <= y < height):
            continue
        gap = abs(rx - x) + halo + size * 0.2
        right = x + gap + draw.textlength(texts[i], font=font) + halo <= width
        draw.text((x + gap if right else x - gap, y), texts[i], font=font, fill=fill,
                  anchor="lm" if right else "rm", stroke_width=halo, stroke_fill=stroke)
    return np.asarray(image)
