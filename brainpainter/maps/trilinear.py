"""Trilinear interpolation of a voxel grid at many points, as one sparse matrix.

Built once for a set of points, it samples every volume of a series with one sparse product
each (a few milliseconds for a million points), where ``scipy.ndimage.map_coordinates`` works
out the same weights again for every volume. Same values as ``map_coordinates(order=1,
mode="nearest", prefilter=False)``: points beyond the grid take its edge.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def trilinear(shape: tuple[int, ...], ijk: NDArray[np.float64]) -> Any:
    """The matrix that interpolates a grid of `shape` (raveled in Fortran order, NIfTI's) at voxel
    coordinates `ijk`.

    Parameters
    ----------
    shape : tuple of int, shape (3,)
        The grid; each axis at least 2 voxels long.
    ijk : ndarray of float, shape (3, n)
        Voxel coordinates of the points.

    Returns
    -------
    scipy.sparse.csr_matrix of float32, shape (n, prod(shape))
        Eight weights per row, summing to 1: ``matrix @ volume.ravel(order="F")`` are the values at
        the points.
    """
    import scipy.sparse as sp

    size = np.asarray(shape[:3], dtype=np.int64)[:, None]
    p = np.clip(ijk, 0.0, size - 1)
    lo = np.minimum(np.floor(p).astype(np.int64), size - 2)
    frac = (p - lo).astype(np.float32)
    n = ijk.shape[1]
    index = np.empty((n, 8), np.int32 if int(np.prod(size)) < 2**31 else np.int64)
    weight = np.empty((n, 8), np.float32)
    for c in range(8):
        bits = [(c >> axis) & 1 for axis in range(3)]
        corner = lo + np.asarray(bits)[:, None]
        index[:, c] = np.ravel_multi_index(tuple(corner), tuple(int(s) for s in size[:, 0]), order="F")
        w = np.ones(n, np.float32)
        for axis, bit in enumerate(bits):
            w *= frac[axis] if bit else 1.0 - frac[axis]
        weight[:, c] = w
    return sp.csr_matrix((weight.ravel(), index.ravel(), np.arange(0, 8 * n + 1, 8)),
                         shape=(n, int(np.prod(size))))
