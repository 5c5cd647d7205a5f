"""Where fsaverage lies in MNI152: the shipped data that volume projection samples at.

Two files in ``brainpainter/data/`` made by ``tools/build_volume_maps.py``, each with its
licence beside it:

``regfusion-fsaverage-mni152.npz``
    The MNI152 position of every fsaverage vertex by registration fusion (RF-ANTs; Wu et al.
    2018, Hum Brain Mapp 39:3793), from the ``regfusion`` 0.1.0 wheel (MIT): int16 arrays ``lh``
    and ``rh`` of shape (163842, 3) in units of ``1 / scale`` mm (``scale``, shape (1,): 200, 0.005 mm steps).
    fsaverage's surfaces are in MNI305, not MNI152: sampling an MNI152 volume at fsaverage's own
    coordinates is off by ~2 mm (up to 4-5 mm); these positions are not.
``fsaverage-aseg-mni152.npz``
    The subcortical structures of the default template (fsaverage's aseg, FreeSurfer licence):
    ``labels`` (uint8 volume, 0 = none, k = ``names[k - 1]``), ``affine`` (voxel -> MNI152 mm,
    through FreeSurfer's MNI305 -> MNI152 transform ``mni305_to_mni152``), ``names``.
"""

from __future__ import annotations

from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError

REGFUSION_FILE = "regfusion-fsaverage-mni152.npz"
ASEG_FILE = "fsaverage-aseg-mni152.npz"
N_FSAVERAGE = 163842
HEMIS = ("lh", "rh")


def _load(name: str) -> dict[str, NDArray[Any]]:
    path = resources.files("brainpainter") / "data" / name
    try:
        with path.open("rb") as f, np.load(f, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except OSError as exc:
        raise BrainPainterError(
            f"brainpainter's data file {name} is missing ({exc}); reinstall brainpainter "
            "(pip install --force-reinstall brainpainter) or rebuild it with tools/build_volume_maps.py."
        ) from None


@cache
def fsaverage_mni152() -> dict[str, NDArray[np.float64]]:
    """MNI152 position of every fsaverage vertex (registration fusion, RF-ANTs).

    Returns
    -------
    dict
        ``{"lh": ndarray (163842, 3), "rh": ndarray (163842, 3)}``, MNI152 mm (x right,
        y anterior, z superior). The first 10242 (2562, 642, 40962) rows are fsaverage5's
        (fsaverage4's, fsaverage3's, fsaverage6's) vertices. Read once and cached: do not modify.
    """
    z = _load(REGFUSION_FILE)
    scale = float(z["scale"].reshape(-1)[0])
    out = {hemi: z[hemi].astype(np.float64) / scale for hemi in HEMIS}
    for xyz in out.values():
        xyz.flags.writeable = False
    return out


@cache
def aseg_mni152() -> tuple[NDArray[np.float64], NDArray[np.int64], tuple[str, ...]]:
    """MNI152 position and structure of every voxel of the template's subcortical structures.

    Returns
    -------
    points : ndarray, shape (n_voxels, 3)
        Voxel centres of fsaverage's aseg (1 mm) in MNI152 mm.
    structure : ndarray of int, shape (n_voxels,)
        Index into `names` of each voxel's structure.
    names : tuple of str
        Structure names as in FreeSurfer's colour table (``"Left-Hippocampus"``), which are
        the region keys of the atlases' subcortical regions.
    """
    z = _load(ASEG_FILE)
    labels = z["labels"]
    ijk = np.argwhere(labels > 0)
    structure = labels[tuple(ijk.T)].astype(np.int64) - 1
    affine = z["affine"]
    points = ijk @ affine[:3, :3].T + affine[:3, 3]
    points.flags.writeable = False
    structure.flags.writeable = False
    return points, structure, tuple(str(n) for n in z["names"])
