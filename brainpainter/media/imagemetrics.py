"""Measurements of rendered images, used by tests and benchmarks.

:func:`border_ratio` measures how jagged the borders between two colours
are: the length of the border between the colour-``a`` and colour-``b``
pixels, divided by its length after a Gaussian smoothing of 1.5 px. A border
that steps along mesh triangles is longer than its smoothed version; one
that follows the label boundary smoothly is only lengthened by the pixel
grid (about 1.05-1.08 for anti-aliased images).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def _contour_length(field: NDArray[Any], valid: NDArray[Any]) -> float:
    """Length (pixels) of the 0.5 iso-line of `field`, counting segments inside `valid` only."""
    from skimage.measure import find_contours

    total = 0.0
    h, w = field.shape
    for c in find_contours(field, 0.5):  # type: ignore[no-untyped-call]
        seg = np.diff(c, axis=0)
        mid = np.rint(0.5 * (c[1:] + c[:-1])).astype(np.int64)
        inside = valid[mid[:, 0].clip(0, h - 1), mid[:, 1].clip(0, w - 1)]
        total += float(np.linalg.norm(seg[inside], axis=1).sum())
    return total


def _srgb_to_linear(c: NDArray[Any]) -> NDArray[Any]:
    c = np.asarray(c, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb(c: NDArray[Any]) -> NDArray[Any]:
    c = np.clip(c, 0.0, 1.0)
    return 255.0 * np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def _blend(rgb: NDArray[Any], a: NDArray[Any], b: NDArray[Any], linear: bool = False) -> tuple[
        NDArray[Any], NDArray[Any]]:
    """Per pixel: the fraction `t` of `a` in a blend of `a` and `b`, and the distance (0-255) to that blend.

    Blends are mixed in sRGB values, or in linear light when `linear`.
    """
    if linear:
        x, a, b = _srgb_to_linear(rgb), _srgb_to_linear(a), _srgb_to_linear(b)
    else:
        x = rgb
    ab = a - b
    t = np.clip(((x - b) @ ab) / float(ab @ ab), 0.0, 1.0)  # 1 at a, 0 at b
    blend = b + t[..., None] * ab
    return t, np.linalg.norm(rgb - (_linear_to_srgb(blend) if linear else blend), axis=-1)


def border_ratio(image: NDArray[Any], a: tuple[int, int, int], b: tuple[int, int, int], *,
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
        Pixels within `tol` (RGB distance) of a blend of `a` and `b` (mixed in
        sRGB values or in linear light) count as region pixels: anti-aliased
        border pixels are such blends.
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
    t, off = _blend(rgb, np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    # a renderer that blends in linear light (and encodes sRGB) puts border pixels on a curve
    t_lin, off_lin = _blend(rgb, np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64),
                            linear=True)
    t = np.where(off_lin < off, t_lin, t)
    off = np.minimum(off, off_lin)
    region = off <= tol
    valid = ndimage.binary_erosion(region, iterations=margin)
    w = region.astype(np.float64)
    smooth = ndimage.gaussian_filter(t * w, sigma) / np.maximum(ndimage.gaussian_filter(w, sigma), 1e-9)
    raw = _contour_length(np.where(region, t, 0.0), valid)
    smoothed = _contour_length(smooth, valid)
    if smoothed <= 0:
        raise ValueError("no border between the two colours in the image")
    return raw / smoothed, raw


def lightness(rgb: NDArray[Any]) -> NDArray[Any]:
    """CIE L* (0-100) of sRGB pixels (0-255), D65 white; shape of `rgb` without its last axis.

    Parameters
    ----------
    rgb : ndarray, shape (..., 3) or (..., 4)
        sRGB values 0-255 (alpha, if any, ignored).
    """
    lin = _srgb_to_linear(np.asarray(rgb, dtype=np.float64)[..., :3])
    y = lin @ np.array([0.2126, 0.7152, 0.0722])
    out: NDArray[Any] = np.where(y > (6 / 29) ** 3, 116.0 * np.cbrt(y) - 16.0, y * (29 / 3) ** 3)
    return out


def lightness_spread(image: NDArray[Any], background: tuple[int, int, int] = (255, 255, 255)) -> float:
    """How much shading varies on the brain: L* 90th minus 10th percentile of the non-background pixels.

    Parameters
    ----------
    image : ndarray of uint8, shape (h, w, 3) or (h, w, 4)
        A render on an opaque `background`.
    background : tuple of int
        Pixels exactly this colour are left out.
    """
    rgb = np.asarray(image)[..., :3]
    brain = ~np.all(rgb == np.asarray(background, dtype=rgb.dtype), axis=-1)
    p10, p90 = np.percentile(lightness(rgb[brain]), [10, 90])
    return float(p90 - p10)


def to_lab(rgb: NDArray[Any]) -> NDArray[Any]:
    """CIELAB (D65) of sRGB pixels (0-255), shape of `rgb` with its last axis 3 (alpha ignored)."""
    lin = _srgb_to_linear(np.asarray(rgb, dtype=np.float64)[..., :3])
    xyz = lin @ np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]).T
    t = xyz / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t * (29 / 6) ** 2 / 3 + 4 / 29)
    out: NDArray[Any] = np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]),
                                  200.0 * (f[..., 1] - f[..., 2])], axis=-1)
    return out


def read_values(rgb: NDArray[Any], cmap: str, vmin: float, vmax: float, n: int = 1024) -> NDArray[Any]:
    """The value each pixel shows: that of the colour of `cmap` nearest to it in CIELAB.

    Parameters
    ----------
    rgb : ndarray, shape (..., 3) or (..., 4)
        sRGB pixels 0-255.
    cmap : str
        A matplotlib colour map, spread over `vmin`..`vmax`.
    n : int
        Colours of the map compared (its resolution).

    Returns
    -------
    ndarray of float, shape of `rgb` without its last axis
    """
    from matplotlib import colormaps
    from scipy.spatial import cKDTree

    t = np.linspace(0.0, 1.0, n)
    table = to_lab(255.0 * colormaps[cmap](t)[:, :3])
    pixels = to_lab(rgb)
    _, nearest = cKDTree(table).query(pixels.reshape(-1, 3))
    out: NDArray[Any] = (vmin + t[nearest] * (vmax - vmin)).reshape(pixels.shape[:-1])
    return out
