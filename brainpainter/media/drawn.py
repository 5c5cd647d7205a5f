"""What the renders show: the regions a view draws, and where the brain is in an image."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.rendering.views import View
from brainpainter.table.region_table import RegionTable

if TYPE_CHECKING:
    from brainpainter.rendering.geometry import SceneGeometry


def drawn_keys(geometry: SceneGeometry, views: Sequence[View]) -> list[str]:
    """Region keys that some view draws, in the scene's slot order.

    The rule is the renderer's: the parts :meth:`SceneGeometry.visible
    <brainpainter.rendering.geometry.SceneGeometry.visible>` gives a view (so a
    brain of structures only, with no cortex, shows its structures in the
    cortex views too), and the regions those parts' faces belong to
    (:attr:`~brainpainter.rendering.geometry.SceneGeometry.part_keys`).
    Hidden regions have no slot and are never drawn; template labels
    outside the atlas (``Left-unknown``) are drawn and listed.

    Parameters
    ----------
    geometry : SceneGeometry
        The scene's geometry (``scene.geometry``).
    views : sequence of View
    """
    drawn: set[str] = set()
    for view in views:
        drawn.update(k for part in geometry.visible(view) for k in geometry.part_keys.get(part.name, ()))
    return [k for k in geometry.keys if k in drawn]


def drawn_kinds(geometry: SceneGeometry, views: Sequence[View]) -> set[str]:
    """The kinds of part (``cortex``, ``tract``, ...) that some view draws (:meth:`SceneGeometry.visible`)."""
    return {part.kind for view in views for part in geometry.visible(view)}


def swatches_needed(table: RegionTable, rows: Sequence[int], views: Sequence[View],
                    geometry: SceneGeometry) -> tuple[bool, bool]:
    """Whether the NaN colour and the missing colour appear in the drawn regions of `rows`.

    Parameters
    ----------
    table : RegionTable
    rows : sequence of int
        Rows of `table` drawn.
    views : sequence of View
    geometry : SceneGeometry
        The geometry the renderer draws (``painter.scene.geometry``): which
        regions a view shows is decided there (:func:`drawn_keys`).

    Returns
    -------
    nan, missing : bool
    """
    keys = set(drawn_keys(geometry, views)) & {r.key for r in table.atlas.regions}  # not 'Left-unknown'
    cols = [j for j, k in enumerate(table.regions) if k in keys]
    values = table.values[np.ix_(list(rows), cols)] if cols else np.zeros((0, 0))
    nan = bool(np.isnan(values).any())
    missing = bool(keys - set(table.regions))
    return nan, missing


def content_box(image: NDArray[Any], background: ColorLike | None, tol: int = 6) -> tuple[int, int, int, int]:
    """Rows and columns holding the brain: ``(top, bottom, left, right)``, end-exclusive.

    ``(0, 0, 0, 0)`` when the image is background only.

    Parameters
    ----------
    image : ndarray of uint8, shape (h, w, 4)
    background : colour or None
        The render's background; None: transparent (alpha decides).
    """
    mask = image[..., 3] > 0
    if background is not None:
        bg = np.round(np.array(to_rgb(background)) * 255).astype(int)
        far = np.zeros(mask.shape, bool)  # |channel - bg| > tol in a channel; uint8: 16x faster than int16
        for c in range(3):
            channel = image[..., c]
            if bg[c] + tol < 255:
                far |= channel > bg[c] + tol
            if bg[c] - tol > 0:
                far |= channel < bg[c] - tol
        mask &= far
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return 0, 0, 0, 0
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def common_crop(images: Sequence[NDArray[Any]], background: ColorLike | None,
                pad: float = 0.02) -> tuple[slice, slice]:
    """One crop holding the brain in all `images` (same shape), with `pad` of the size around it.

    Images with nothing but background are ignored; when all are, nothing is cropped.
    """
    h, w = images[0].shape[:2]
    boxes = np.array([b for b in (content_box(im, background) for im in images) if b[1] > b[0]]
                     or [(0, h, 0, w)])
    p = round(pad * max(h, w))
    top, bottom = max(0, boxes[:, 0].min() - p), min(h, boxes[:, 1].max() + p)
    left, right = max(0, boxes[:, 2].min() - p), min(w, boxes[:, 3].max() + p)
    return slice(int(top), int(bottom)), slice(int(left), int(right))
