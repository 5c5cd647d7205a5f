"""Packed streamlines: resampling to a fixed number of points, consistent orientation, subsampling.

Streamlines arrive packed as nibabel's ``ArraySequence`` does it: one points
array plus offsets and lengths, never a list of arrays. After resampling every
streamline has the same number of points, so a bundle is one array of shape
``(n_streamlines, n_points, 3)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def resample(points: NDArray[Any], offsets: NDArray[Any], lengths: NDArray[Any],
             n_points: int) -> NDArray[Any]:
    """Resample packed streamlines to `n_points` equally spaced points along each (arc length).

    The same as dipy's ``set_number_of_points``, vectorised over all streamlines in numpy.

    Parameters
    ----------
    points : ndarray of float, shape (n_total_points, 3)
    offsets : ndarray of int, shape (n_streamlines,)
        Index of each streamline's first point.
    lengths : ndarray of int, shape (n_streamlines,)
        Points per streamline (at least 1).
    n_points : int
        At least 2.

    Returns
    -------
    ndarray of float32, shape (n_streamlines, n_points, 3)
    """
    pts = np.asarray(points, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    ln = np.asarray(lengths, dtype=np.int64)
    n = len(off)
    if n == 0:
        return np.zeros((0, n_points, 3), np.float32)
    # segment lengths and cumulative arc length per point, restarting at each streamline
    seg = np.zeros(len(pts))
    if len(pts) > 1:
        seg[1:] = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    seg[off] = 0.0
    cum = np.cumsum(seg)
    cum -= np.repeat(cum[off], ln)  # arc length from each streamline's start
    total = cum[off + ln - 1]
    t = np.linspace(0.0, 1.0, n_points)[None, :] * total[:, None]  # (n, n_points) target arc lengths
    # for each target, the segment it falls in: searchsorted within each streamline
    key = cum + np.repeat(np.arange(n) * (total.max() + 1.0), ln)  # globally increasing
    tk = t + (np.arange(n) * (total.max() + 1.0))[:, None]
    hi = np.searchsorted(key, tk.ravel(), side="left").reshape(n, n_points)
    first, last = off[:, None], (off + ln - 1)[:, None]
    hi = np.clip(hi, first + 1, np.maximum(last, first + 1))
    hi = np.minimum(hi, last)
    lo = np.maximum(hi - 1, first)
    span = cum[hi] - cum[lo]
    w = np.where(span > 0, (t - cum[lo]) / np.where(span > 0, span, 1.0), 0.0)
    w = np.clip(w, 0.0, 1.0)[..., None]
    out: NDArray[Any] = (pts[lo] * (1.0 - w) + pts[hi] * w).astype(np.float32)
    return out


def orient(lines: NDArray[Any]) -> NDArray[Any]:
    """Flip streamlines so a bundle's run the same way (start near start), as tractometry needs.

    First each streamline is flipped so its end-to-end vector points along the
    bundle's main axis (signed so that axis points to +x, +y or +z, whichever
    is largest); then, once, each is flipped where its reverse lies closer to
    the bundle's mean streamline (mean direct-flip distance, as dipy's
    ``orient_by_streamline`` does).

    Parameters
    ----------
    lines : ndarray of float, shape (n_streamlines, n_points, 3)

    Returns
    -------
    ndarray, same shape and dtype
    """
    x = np.array(lines, copy=True)
    if len(x) == 0:
        return x
    ends = (x[:, -1] - x[:, 0]).astype(np.float64)
    _, _, vt = np.linalg.svd(ends, full_matrices=False)
    axis = vt[0]
    axis = axis * (1.0 if axis[np.argmax(np.abs(axis))] > 0 else -1.0)
    flip = ends @ axis < 0
    x[flip] = x[flip, ::-1]
    mean = x.mean(axis=0)
    same = np.linalg.norm(x - mean, axis=2).mean(axis=1)
    rev = np.linalg.norm(x[:, ::-1] - mean, axis=2).mean(axis=1)
    flip = rev < same
    x[flip] = x[flip, ::-1]
    return x


def pick(total: int, budget: int, seed: int = 0) -> NDArray[Any] | None:
    """Indices (sorted) of `budget` streamlines drawn at random from `total`; None if all fit.

    Parameters
    ----------
    total, budget : int
    seed : int
        The same seed picks the same streamlines (every worker of a run draws the same).
    """
    if total <= budget:
        return None
    chosen: NDArray[Any] = np.sort(np.random.default_rng(seed).choice(total, budget, replace=False))
    return chosen


def direction_rgb(lines: NDArray[Any]) -> NDArray[Any]:
    """Direction colour at each point: RGB = |dx|, |dy|, |dz| of the unit tangent (red = left-right).

    Parameters
    ----------
    lines : ndarray of float, shape (n_streamlines, n_points, 3)

    Returns
    -------
    ndarray of float32, shape (n_streamlines, n_points, 3)
        Components 0-1.
    """
    t = np.gradient(np.asarray(lines, dtype=np.float64), axis=1)
    norm = np.linalg.norm(t, axis=2, keepdims=True)
    rgb: NDArray[Any] = np.abs(t / np.where(norm > 0, norm, 1.0)).astype(np.float32)
    return rgb


#: Levels per channel of the direction colours' slots: a channel is off by at most 1/32 (8 of 255);
#: at most 3 * 17**2 - 3 * 17 + 1 = 817 slots are used (colours whose largest channel is 1).
DIRECTION_LEVELS = 17


def direction_bins(lines: NDArray[Any], levels: int = DIRECTION_LEVELS) -> tuple[NDArray[Any], NDArray[Any]]:
    """Direction colours quantised to a fixed set of palette slots.

    Parameters
    ----------
    lines : ndarray of float, shape (n_streamlines, n_points, 3)
    levels : int
        Levels per colour channel.

    Returns
    -------
    bins : ndarray of int64, shape (n_streamlines, n_points)
        Slot of each point's direction colour, ``0 .. levels**3 - 1``.
    colors : ndarray of float32, shape (levels**3, 3)
        sRGB 0-1 of each slot. The direction colour (|dx|, |dy|, |dz|) is scaled so its
        largest channel is 1 (a left-right streamline is pure red, a diagonal one yellow)
        and then quantised, each channel to within ``1 / (2 * (levels - 1))``.
    """
    rgb = direction_rgb(lines).astype(np.float64)
    top = rgb.max(axis=-1, keepdims=True)
    rgb = np.where(top > 0, rgb / np.where(top > 0, top, 1.0), 1.0)
    q = np.clip(np.rint(rgb * (levels - 1)), 0, levels - 1).astype(np.int64)
    bins = (q[..., 0] * levels + q[..., 1]) * levels + q[..., 2]
    grid = np.stack(np.meshgrid(*[np.arange(levels)] * 3, indexing="ij"), -1).reshape(-1, 3) / (levels - 1)
    top = grid.max(axis=1, keepdims=True)
    colors = (grid / np.where(top > 0, top, 1.0)).astype(np.float32)
    return bins, colors
