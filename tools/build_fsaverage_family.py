"""Build ``brainpainter/data/fsaverage_family.npz`` from FreeSurfer's fsaverage (run once; output committed).

What it holds (all derived from FreeSurfer 7.3.2's ``subjects/fsaverage``; see
``brainpainter/data/fsaverage_family.LICENSE.txt``):

``parents`` : int32, shape (163830, 2)
    The two parents of every fsaverage vertex ``i >= 12``: the endpoints of the
    edge of the coarser icosahedron that vertex ``i`` subdivides. fsaverage is
    an icosahedron subdivided 7 times; vertex ``i`` of fsaverageK is vertex
    ``i`` of fsaverage for ``i < n_K`` (``n_K = 10 * 4**K + 2``), and each
    vertex added at level ``L+1`` is the midpoint of an edge of level ``L``:
    its two nearest level-``L`` vertices on the sphere (checked: the third
    nearest is always at least 1.36 times farther).
``{lh,rh}_cortex`` : uint8, packed bits of 163842
    ``?h.cortex.label`` (the medial wall is 0).
``{lh,rh}_sulc``, ``{lh,rh}_curv`` : uint8, packed bits of 163842
    ``?h.sulc > 0`` (in a sulcus) and ``?h.curv > 0`` (concave): the two greys of an underlay.

Usage: ``python tools/build_fsaverage_family.py /path/to/freesurfer/subjects``
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
from scipy.spatial import cKDTree

OUT = Path(__file__).resolve().parents[1] / "brainpainter" / "data" / "fsaverage_family.npz"
COUNTS = [10 * 4**k + 2 for k in range(8)]


def parents(sphere: np.ndarray) -> np.ndarray:
    unit = sphere / np.linalg.norm(sphere, axis=1, keepdims=True)
    out = []
    for lo, hi in itertools.pairwise(COUNTS):
        dist, idx = cKDTree(unit[:lo]).query(unit[lo:hi], k=3)
        if (dist[:, 2] / dist[:, 1]).min() < 1.2 or (dist[:, 1] / dist[:, 0]).max() > 1.1:
            raise SystemExit(f"level {lo}->{hi}: not a subdivided icosahedron")
        out.append(np.sort(idx[:, :2], axis=1))
    return np.concatenate(out).astype(np.int32)


def main(subjects: Path) -> None:
    fs = subjects / "fsaverage"
    lh, faces = nib.freesurfer.read_geometry(str(fs / "surf" / "lh.sphere"))
    rh, faces_rh = nib.freesurfer.read_geometry(str(fs / "surf" / "rh.sphere"))
    if not np.array_equal(faces, faces_rh) or not np.allclose(lh, rh):
        raise SystemExit("lh and rh spheres differ")
    arrays: dict[str, np.ndarray] = {"parents": parents(lh)}
    n = COUNTS[-1]
    for hemi in ("lh", "rh"):
        cortex = np.zeros(n, bool)
        cortex[nib.freesurfer.read_label(str(fs / "label" / f"{hemi}.cortex.label"))] = True
        arrays[f"{hemi}_cortex"] = np.packbits(cortex)
        for m in ("sulc", "curv"):
            morph = nib.freesurfer.read_morph_data(str(fs / "surf" / f"{hemi}.{m}"))
            arrays[f"{hemi}_{m}"] = np.packbits(morph > 0)
    np.savez_compressed(OUT, **arrays)
    print(f"wrote {OUT} ({OUT.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("../shared/data/freesurfer/subjects"))
