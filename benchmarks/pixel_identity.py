"""Pixel identity of a corpus of images between two checkouts (issue 43: a refactor keeps every image).

Renders the corpus below small, through the command line (in process, click's runner) and the Python API,
and saves every image as an array::

    PYTHONPATH=<checkout>:<checkout>/plugins/atlases:<checkout>/plugins/renderers:<checkout>/tools \\
        python3 benchmarks/pixel_identity.py save /tmp/base.npz        # in a checkout of main
    python3 benchmarks/pixel_identity.py save /tmp/new.npz             # in this one
    python3 benchmarks/pixel_identity.py compare /tmp/base.npz /tmp/new.npz

The corpus: a DK table; a Destrieux table with the subcortical views; a map with a threshold and an outline;
a CIFTI dscalar on the flat maps (../shared/data/fslr); dipy's bundles with bundle values; the Schaefer-400
group connectome (brainspace's matrix); a map with a contour and tracts; the mouse atlas; a movie frame;
a volume's clusters as surfaces; a figure. Items whose data is missing on this machine are left out
(and said so).
"""

from __future__ import annotations

import importlib.metadata
import sys
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data"
FS = SHARED / "freesurfer" / "subjects" / "fsaverage" / "surf"
SIZE = "160x120"
SMALL = ["--size", SIZE, "-q"]


def _cli(args: list[str]) -> None:
    from click.testing import CliRunner

    from brainpainter.cli.main import cli

    result = CliRunner().invoke(cli, args)
    if result.exit_code != 0:
        raise RuntimeError(f"{args}: {result.output} {result.exception!r}")


def _pngs(folder: Path) -> dict[str, np.ndarray]:
    from PIL import Image

    return {p.stem: np.asarray(Image.open(p)) for p in sorted(folder.glob("*.png"))}


def _render(tmp: Path, name: str, args: list[str]) -> dict[str, np.ndarray]:
    out = tmp / name
    _cli(["render", *args, "--out", str(out), *SMALL])
    return _pngs(out)


def dk(tmp: Path) -> dict[str, np.ndarray]:
    return _render(tmp, "dk", [str(REPO / "examples" / "brainpainter_dk.csv"), "--rows", "stage-3"])


def destrieux(tmp: Path) -> dict[str, np.ndarray]:
    from brainpainter.atlas.registry import get_atlas

    keys = get_atlas("destrieux").keys
    values = (np.arange(len(keys)) * 7 % 23) / 7.0
    path = tmp / "destrieux.csv"
    path.write_text("Image-name-unique," + ",".join(keys) + "\nd," + ",".join(f"{v:.3f}" for v in values))
    return _render(tmp, "destrieux", [str(path), "--atlas", "destrieux",
                                      "--views", "subcortical,subcortical-dorsal,lateral-left"])


def map_threshold_outline(tmp: Path) -> dict[str, np.ndarray]:
    return _render(tmp, "map", ["--lh", str(FS / "lh.sulc"), "--rh", str(FS / "rh.sulc"),
                                "--threshold", "0.3", "--outline", "dk",
                                "--views", "lateral-left,medial-right"])


def cifti_flat(tmp: Path) -> dict[str, np.ndarray]:
    path = SHARED / "fslr" / "MSMSulc.refsulc.164k_fs_LR.dscalar.nii"
    return _render(tmp, "cifti", [str(path), "--views", "flat"])


def _bundles(tmp: Path) -> Path:
    import dipy

    folder = tmp / "dipy"
    with zipfile.ZipFile(Path(dipy.__file__).parent / "data" / "files" / "minimal_bundles.zip") as z:
        z.extractall(folder)
    np.savetxt(tmp / "place.txt", [[1, 0, 0, 0], [0, 1, 0, -10], [0, 0, 1, 25], [0, 0, 0, 1]])
    return folder / "sub_1"


def tracts(tmp: Path) -> dict[str, np.ndarray]:
    bundles = _bundles(tmp)
    (tmp / "bundles.csv").write_text("Image-name-unique,AF_left,CST_right,CC_ForcepsMajor\na,0.2,0.5,0.9\n")
    return _render(tmp, "tracts", [str(tmp / "bundles.csv"), "--tracts", str(bundles), "--tracts-space",
                                   "fsaverage", "--tracts-affine", str(tmp / "place.txt"),
                                   "--views", "subcortical-dorsal,lateral-left"])


def schaefer400(tmp: Path) -> dict[str, np.ndarray]:
    import brainpainter
    from brainpainter.atlas.model import load_atlas_dir

    dist = importlib.metadata.distribution("brainspace")
    matrix = dist.locate_file("brainspace/datasets/matrices/holdout_group/"
                              "schaefer_400_mean_connectivity_matrix.csv")
    atlas = load_atlas_dir(REPO / "plugins" / "atlases" / "brainpainter-atlas-schaefer-yeo"
                           / "bp_atlas_schaefer_yeo" / "data" / "schaefer400_7n")
    result = brainpainter.render(None, atlas, connectome=str(matrix), edge_threshold="99%",
                                 views="dorsal,lateral-left", width=160, height=120, progress=False)
    return {"_".join(key): img for key, img in result.images.items()}


def map_contour_tracts(tmp: Path) -> dict[str, np.ndarray]:
    bundles = _bundles(tmp)
    return _render(tmp, "mct", ["--lh", str(FS / "lh.sulc"), "--rh", str(FS / "rh.sulc"),
                                "--contour", f"{FS / 'lh.curv'},{FS / 'rh.curv'}", "--contour-levels", "0",
                                "--contour-color", "red", "--tracts", str(bundles), "--tracts-space",
                                "fsaverage", "--tracts-affine", str(tmp / "place.txt"),
                                "--views", "lateral-left,dorsal"])


def mouse(tmp: Path) -> dict[str, np.ndarray]:
    import brainpainter
    from brainpainter.atlas.model import load_atlas_dir

    atlas = load_atlas_dir(REPO / "plugins" / "atlases" / "brainpainter-atlas-mouse" / "bp_atlas_mouse"
                           / "data" / "mouse")
    table = SHARED / "mouse" / "brainpainter2021" / "mouse_template.csv"
    result = brainpainter.render(str(table), atlas, rows=[0], views="top,cortical-outer,subcortical",
                                 width=160, height=120, progress=False)
    return {"_".join(key): img for key, img in result.images.items()}


def blobs(tmp: Path) -> dict[str, np.ndarray]:
    """A volume's clusters as surfaces (--volume-surface): two Gaussian blobs, one negative, in MNI152."""
    import nibabel as nib

    ijk = np.indices((91, 109, 91)).reshape(3, -1).T
    affine = np.array([[-2, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]], float)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    data = sum(sign * 5 * np.exp(-np.sum((xyz - c) ** 2, axis=1) / 60)
               for sign, c in ((1, (-40, -20, 50)), (-1, (30, 10, 20))))
    path = tmp / "z.nii.gz"
    nib.save(nib.Nifti1Image(data.reshape(91, 109, 91).astype(np.float32), affine), path)
    return _render(tmp, "blobs", ["--volume-surface", str(path), "--threshold", "2",
                                  "--views", "dorsal,lateral-left"])


def movie_frame(tmp: Path) -> dict[str, np.ndarray]:
    from PIL import Image

    out = tmp / "movie.gif"
    _cli(["movie", str(REPO / "examples" / "brainpainter_dk.csv"), "--rows", "stage-1,stage-2",
          "--frames-per-step", "3", "--views", "lateral-left", "-o", str(out), *SMALL])
    with Image.open(out) as gif:
        gif.seek(1)  # a frame between two rows (blended colours)
        return {"frame1": np.asarray(gif.convert("RGB"))}


def figure(tmp: Path) -> dict[str, np.ndarray]:
    from PIL import Image

    out = tmp / "figure.png"
    _cli(["figure", str(REPO / "examples" / "brainpainter_dk.csv"), "--rows", "stage-2,stage-4", "--grid",
          "--views", "lateral-left,medial-left", "--dpi", "60", "--label", "z", "-o", str(out), *SMALL])
    return {"figure": np.asarray(Image.open(out))}


CORPUS: dict[str, Callable[[Path], dict[str, np.ndarray]]] = {
    "dk": dk, "destrieux": destrieux, "map_threshold_outline": map_threshold_outline,
    "cifti_flat": cifti_flat,
    "tracts": tracts, "schaefer400": schaefer400, "map_contour_tracts": map_contour_tracts, "mouse": mouse,
    "blobs": blobs, "movie_frame": movie_frame, "figure": figure,
}


def save(path: Path, only: list[str]) -> None:
    arrays: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, make in CORPUS.items():
            if only and name not in only:
                continue
            folder = Path(tmp) / name
            folder.mkdir()
            try:
                images = make(folder)
            except (FileNotFoundError, ImportError, importlib.metadata.PackageNotFoundError) as exc:
                print(f"{name}: left out ({exc})")
                continue
            for key, img in images.items():
                arrays[f"{name}/{key}"] = img
            print(f"{name}: {len(images)} image(s)")
    np.savez_compressed(path, **arrays)


def compare(a: Path, b: Path) -> int:
    base, new = np.load(a), np.load(b)
    differ = 0
    for key in sorted(set(base) | set(new)):
        if key not in base or key not in new:
            print(f"{key}: only in {'new' if key not in base else 'base'}")
            differ += 1
            continue
        x, y = base[key], new[key]
        if x.shape != y.shape:
            print(f"{key}: shape {x.shape} vs {y.shape}")
            differ += 1
        elif not np.array_equal(x, y):
            d = np.abs(x.astype(int) - y.astype(int)).max(axis=-1) if x.ndim == 3 else x != y
            print(f"{key}: {int((d > 0).sum())} pixels differ (max {int(d.max())})")
            differ += 1
        else:
            print(f"{key}: identical {x.shape}")
    print(f"{len(set(base) | set(new))} images, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    if sys.argv[1] == "save":
        save(Path(sys.argv[2]), sys.argv[3:])
    else:
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])))
