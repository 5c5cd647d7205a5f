"""Measurements of rendered images, used by tests and benchmarks.

:func:`border_ratio` measures how jagged the borders between two colours
are: the length of the border between the colour-``a`` and colour-``b``
pixels, divided by its length after a Gaussian smoothing of 1.5 px. A border
that steps along mesh triangles is longer than its smoothed version; one
that follows the label boundary smoothly is only lengthened by the pixel
grid (about 1.05-1.08 for anti-aliased images).
"""

from __future__ import annotations

import numpy as np


def _contour_length(field: np.ndarray, valid: np.ndarray) -> float:
    """Length (pixels) of the 0.5 iso-line of `field`, counting segments inside `valid` only."""
    from skimage.measure import find_contours

    total = 0.0
    h, w = field.shape
    for c in find_contours(field, 0.5):
        seg = np.diff(c, axis=0)
        mid = np.rint(0.5 * (c[1:] + c[:-1])).astype(np.int64)
        inside = valid[mid[:, 0].clip(0, h - 1), mid[:, 1].clip(0, w - 1)]
        total += float(np.linalg.norm(seg[inside], axis=1).sum())
    return total


def border_ratio(image: np.ndarray, a: tuple[int, int, int], b: tuple[int, int, int], *,
                 sigma: float = 1.5, tol: float = 12.0, margin: int = 3) -> tuple[float, float]:
    """Border length between two colours over the same after Gaussian smoothing.

    Parameters
    ----------
    image : ndarray of uint8, shape (h, w, 3) or (h, w, 4)
        A flat-shaded render whose regions are coloured `a` or `b`.
    a, b : tuple of int
        The two region colours (0-255).
    sigma : float
        Gaussian smoothing, pixels.
    tol : float
        Pixels within `tol` (RGB distance) of the segment from `a` to `b`
        count as region pixels (anti-aliased border pixels are blends of `a`
        and `b`).
    margin : int
        Region pixels this close to a non-region pixel (background, silhouette,
        medial wall, other colours) are left out, so only ``a``-``b`` borders count.

    Returns
    -------
    ratio : float
        Border length / smoothed border length (1.0 for a perfectly smooth border).
    length : float
        Border length, pixels.
    """
    from scipy import ndimage

    rgb = np.asarray(image, dtype=np.float64)[..., :3]
    a_ = np.asarray(a, dtype=np.float64)
    b_ = np.asarray(b, dtype=np.float64)
    ab = a_ - b_
    t = np.clip(((rgb - b_) @ ab) / float(ab @ ab), 0.0, 1.0)  # 1 at a, 0 at b
    off = np.linalg.norm(rgb - (b_ + t[..., None] * ab), axis=-1)
    region = off <= tol
    valid = ndimage.binary_erosion(region, iterations=margin)
    w = region.astype(np.float64)
    smooth = ndimage.gaussian_filter(t * w, sigma) / np.maximum(ndimage.gaussian_filter(w, sigma), 1e-9)
    raw = _contour_length(np.where(region, t, 0.0), valid)
    smoothed = _contour_length(smooth, valid)
    if smoothed <= 0:
        raise ValueError("no border between the two colours in the image")
    return raw / smoothed, raw
