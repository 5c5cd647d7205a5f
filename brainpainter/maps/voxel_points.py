"""Where a volume is sampled: voxel coordinates of world points, kept per grid and point set.

Every figure of an MNI152 volume samples it at the same points (the cortex's registration-fusion
positions and the depths of ``--projection`` around them, the subcortical structures' voxels, a
slice panel's pixels: :func:`brainpainter.maps.sections.sample_plane`); only the voxels' values
change. So the voxel coordinates of each point set in a grid (its affine and shape) are worked
out once in a process and kept (:data:`VOXEL_MEMO`, read-only): ~0.04 s of a figure before, and
no ``np.linalg.inv`` either, whose LAPACK call woke OpenBLAS's worker thread, which then spun a
core for a while (~0.1 s of CPU after each such call).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable

import numpy as np
from numpy.typing import NDArray

from brainpainter.io.memo import Memo

#: Voxel coordinates kept (a grid's cortex at three depths is 25 MB, a slice panel's pixels ~3 MB).
VOXEL_MEMO = Memo(max_bytes=128 * 1024 * 1024)


def voxel_coordinates(affine: NDArray[np.float64], shape: tuple[int, ...], points: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Voxel coordinates of world points, shape (3, n), and which points lie inside the grid.

    Parameters
    ----------
    affine : ndarray, shape (4, 4)
        Voxel indices to world millimetres.
    shape : tuple of int
        The grid's (its first three axes count).
    points : ndarray, shape (n, 3)
        World millimetres.
    """
    inverse = np.linalg.inv(affine)
    ijk = np.empty((3, len(points)))
    for r in range(3):   # element-wise: a (n, 3) @ (3, 3) product is slower through BLAS threads
        ijk[r] = points[:, 0] * inverse[r, 0] + points[:, 1] * inverse[r, 1] + points[:, 2] * inverse[r, 2]
        ijk[r] += inverse[r, 3]
    size = np.asarray(shape[:3], dtype=np.float64)[:, None]
    inside = ((ijk >= -0.5) & (ijk <= size - 0.5)).all(axis=0)
    return ijk, inside


def kept_voxel_coordinates(affine: NDArray[np.float64], shape: tuple[int, ...], name: Hashable,
                           points: Callable[[], NDArray[np.float64]]
                           ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """:func:`voxel_coordinates` of the point set `name` (``points()`` gives it, always the same for
    one name), kept per grid (read-only)."""
    a = np.asarray(affine, dtype=np.float64)
    key = (name, a.tobytes(), tuple(int(s) for s in shape[:3]))
    return VOXEL_MEMO.get(key, lambda: voxel_coordinates(a, shape, points()))
