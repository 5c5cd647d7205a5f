"""docs/atlases/mouse-vs-original.png: the mouse atlas (brainpainter-atlas-mouse) beside the original's.

    python docs/atlases/make_mouse_comparison.py [/path/to/brainpainter2021]

Renders row Image_0 of the original's ``mouse_template.csv`` with the
distribution's data folder (no install needed) in the original's three views
(``top``, ``cortical-outer`` seen from the right as the original's image is,
``subcortical``) and puts each beside the original's image of the same view
(``reference-images/mouse-*.png``; BrainPainter, Marinescu et al. (2019),
arXiv:1905.08627, CC-BY 3.0; scaled down). The original's images show another
row of values, so the colours differ; orientation and framing are what to compare.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from PIL import Image, ImageDraw

from brainpainter.atlas.model import load_atlas_dir
from brainpainter.rendering.run import render

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
DATA = REPO / "plugins" / "atlases" / "brainpainter-atlas-mouse" / "bp_atlas_mouse" / "data" / "mouse"
VIEWS = (("dorsal", "top", "mouse-top.png"), ("lateral-right", "cortical-outer", "mouse-cort-outer.png"),
         ("subcortical", "subcortical", "mouse-subcortical.png"))
W, H = 480, 360


def main(source: Path, out: Path = HERE / "mouse-vs-original.png") -> Path:
    atlas = load_atlas_dir(DATA)
    sheet = Image.new("RGB", (2 * W, len(VIEWS) * H + 24), "white")
    draw = ImageDraw.Draw(sheet)
    draw.text((W // 2 - 60, 5), "brainpainter (this repository)", fill="black")
    draw.text((W + W // 2 - 80, 5), "original BrainPainter (2021), CC-BY 3.0", fill="black")
    with tempfile.TemporaryDirectory() as tmp:
        render(source / "mouse_template.csv", atlas, out=tmp, rows="Image_0",
               views=",".join(v for v, _, _ in VIEWS), width=W, height=H, progress=False)
        for i, (view, label, ref) in enumerate(VIEWS):
            ours = Image.open(Path(tmp) / f"Image_0_{view}.png").convert("RGB")
            theirs = Image.open(source / "reference-images" / ref).convert("RGB")
            theirs = theirs.resize((W, H), Image.LANCZOS)
            sheet.paste(ours, (0, 24 + i * H))
            sheet.paste(theirs, (W, 24 + i * H))
            draw.text((8, 30 + i * H), f"--views {label} ({view})", fill="black")
    sheet.quantize(256, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)
    return out


if __name__ == "__main__":
    default = REPO.parent / "shared" / "data" / "mouse" / "brainpainter2021"
    print("wrote", main(Path(sys.argv[1]) if len(sys.argv) > 1 else default))
