"""Time `atlas add --meshes` on the original BrainPainter's mouse meshes and one render of each of its views.

    python benchmarks/mesh_atlas.py [/path/to/shared/data/mouse/brainpainter2021]

Prints seconds for: reading + welding + checking the 54 PLY files (build_mesh_atlas),
and rendering mouse_template.csv row Image_0 in top, cortical-outer and subcortical
(1200x900, default quality, the Blender renderer) with the atlas just built.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from brainpainter.atlas.meshfolder import build_mesh_atlas
from brainpainter.atlas.model import load_atlas_dir
from brainpainter.rendering.run import render


def main(source: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "mouse"
        out.mkdir()
        t0 = time.perf_counter()
        build_mesh_atlas("mouse", [source / "Mice_atlas_pial"],
                         subcortical=[source / "mouse_subcortical_ply"], orientation="RAS",
                         surface_also=("Left-Cerebellum", "Right-Cerebellum"), out=out)
        t1 = time.perf_counter()
        print(f"build_mesh_atlas (54 PLY files): {t1 - t0:.1f} s")
        render(source / "mouse_template.csv", load_atlas_dir(out), out=Path(tmp) / "png", rows="Image_0",
               views="top,cortical-outer,subcortical", progress=False)
        print(f"render 3 views (incl. scene load): {time.perf_counter() - t1:.1f} s")


if __name__ == "__main__":
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "mouse" / "brainpainter2021"
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else default)
