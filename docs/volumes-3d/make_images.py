"""Make the images of docs/maps-volumes.md's "Blobs and cutaways in 3-D" (small PNGs).

    python docs/volumes-3d/make_images.py

A synthetic z-map on nilearn's MNI152 2 mm grid (six Gaussian blobs of both signs) drawn as blobs,
the bundled DK example cut open, and four frames of a movie whose cut plane sweeps from left to right
through the DK example's opaque cortex with the blobs inside; the blobs alone beside their slice and
glass-brain panels, all on the blobs' bar.
"""

from __future__ import annotations

from pathlib import Path
from tempfile import TemporaryDirectory

import nibabel as nib
import numpy as np
from PIL import Image, ImageSequence

import brainpainter

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parents[1] / "examples" / "brainpainter_dk.csv"
#: (centre MNI mm, sigma mm, peak) of each blob
BLOBS = (((40, -20, 52), 7, 5.5), ((-26, -22, -12), 5, -4.0), ((-12, -18, 8), 5, 4.5),
         ((18, -88, 4), 8, 3.8), ((-44, 22, 22), 6, -3.6), ((46, -62, 30), 5, 3.0))


def zmap(path: Path) -> Path:
    from nilearn import datasets

    template = datasets.load_mni152_template(resolution=2)
    affine = np.asarray(template.affine)
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in template.shape], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    data = sum(peak * np.exp(-((xyz - np.asarray(c)) ** 2).sum(-1) / (2 * s * s)) for c, s, peak in BLOBS)
    nib.save(nib.Nifti1Image(np.asarray(data, np.float32), affine), path)
    return path


def shrink(path: Path, width: int) -> None:
    with Image.open(path) as im:
        small = im.convert("RGB").resize((width, round(im.height * width / im.width)), Image.LANCZOS)
    small.save(path, optimize=True)


def blob_panels(z: Path) -> None:
    """The blobs from above with an axial slice and the axial projection of the same volume."""
    brainpainter.figure(None, out=HERE / "blobs_panels.png", volume_surface=str(z), threshold=2.3,
                        views="dorsal", slices="z=52", projections="z", width=600, height=450, label="z",
                        dpi=150, progress=False)
    shrink(HERE / "blobs_panels.png", 1000)


def main() -> None:
    with TemporaryDirectory() as tmp:
        z = zmap(Path(tmp) / "zstat.nii.gz")
        brainpainter.figure(None, out=HERE / "blobs.png", volume_surface=str(z), threshold=2.3,
                            views="dorsal,cutaway-left,cutaway-corner", width=600, height=450,
                            label="z", dpi=150, progress=False)
        shrink(HERE / "blobs.png", 1200)
        brainpainter.figure(str(EXAMPLE), atlas="dk", rows="stage-4", out=HERE / "cutaway_dk.png",
                            views="lateral-left,cutaway-dorsal,cutaway-corner", clip="x<0", width=600,
                            height=450, dpi=150, progress=False)
        shrink(HERE / "cutaway_dk.png", 1200)
        movie = Path(tmp) / "sweep.gif"
        brainpainter.movie(str(EXAMPLE), atlas="dk", rows="stage-4", out=movie, views="lateral-left",
                           clip_sweep="x", volume_surface=str(z), threshold=2.3, cortex="opaque",
                           frames_per_step=6, width=400, height=300, progress=False)
        with Image.open(movie) as gif:
            frames = [f.convert("RGB") for f in ImageSequence.Iterator(gif)][::2][:4]
        sheet = Image.new("RGB", (frames[0].width * len(frames), frames[0].height), "white")
        for k, frame in enumerate(frames):
            sheet.paste(frame, (k * frame.width, 0))
        sheet.save(HERE / "sweep.png", optimize=True)
        shrink(HERE / "sweep.png", 1400)
        blob_panels(z)


if __name__ == "__main__":
    main()
