"""Fidelity of the decimated default template against the full-resolution surface.

Builds a full-resolution DK template of fsaverage from ../shared/data into a
temporary folder, renders the lateral-left view of the bundled example (every
row) at 1200x900, default quality, with both templates, and prints the SSIM
(scikit-image, on the RGB image) per row. Target: SSIM >= 0.97.

    python benchmarks/template_fidelity.py [--surface pial] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FSAVERAGE = REPO.parent / "shared" / "data" / "freesurfer" / "subjects" / "fsaverage"


def main() -> None:
    from skimage.metrics import structural_similarity

    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.scene import RenderSettings
    from brainpainter.rendering.views import get_view
    from brainpainter.table.region_table import read_table
    from brainpainter_builder.build import build_template

    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--surface", default="pial")
    parser.add_argument("--views", default="lateral-left")
    parser.add_argument("--keep", type=Path, default=None, help="also save the PNG pairs here")
    args = parser.parse_args()

    table = read_table(REPO / "examples" / "brainpainter_dk.csv", atlas="dk")
    scale = make_scale()
    settings = RenderSettings(width=1200, height=900, quality="default")
    with tempfile.TemporaryDirectory() as tmp:
        full = build_template(FSAVERAGE, Path(tmp) / "full", atlases=("dk",), target_faces=None,
                              max_size_mb=None, progress=False, name="fsaverage-full")
        results = []
        for view_name in args.views.split(","):
            view = get_view(view_name)
            images = {}
            for label, template in (("decimated", "fsaverage"), ("full", str(full))):
                with Painter("dk", template, args.surface, settings=settings) as painter:
                    images[label] = [painter.paint(table.row(i), view, scale)
                                     for i in range(len(table.images))]
            for i, image in enumerate(table.images):
                a, b = images["decimated"][i][..., :3], images["full"][i][..., :3]
                ssim = structural_similarity(a, b, channel_axis=-1, data_range=255)
                results.append({"view": view_name, "image": image, "ssim": round(float(ssim), 4)})
                if args.keep:
                    from PIL import Image

                    args.keep.mkdir(parents=True, exist_ok=True)
                    pair = np.concatenate([a, b], axis=1)
                    Image.fromarray(pair).save(args.keep / f"{image}_{view_name}.png")
    print(json.dumps({"surface": args.surface, "results": results,
                      "min_ssim": min(r["ssim"] for r in results)}, indent=2))


if __name__ == "__main__":
    main()
