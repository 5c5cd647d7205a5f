"""Make bp_atlas_mouse/data/mouse from the original BrainPainter's mouse meshes.

    python build_data.py [/path/to/brainpainter2021]

The folder holds ``Mice_atlas_pial/{lh,rh}.pial.Mice.REGION.ply`` (the outer
surface: 20 areas per hemisphere) and ``mouse_subcortical_ply/{Left,Right}-REGION.ply``
(7 structures per hemisphere), from github.com/razvanmarinescu/brain-coloring
(commit 822a7c2). Uses the same code as ``brainpainter atlas add mouse
--meshes Mice_atlas_pial --subcortical-meshes mouse_subcortical_ply --also-surface
Left-Cerebellum --also-surface Right-Cerebellum --out DIR``: the triangle soups
are welded, two stray copies of the right perirhinal area (exported at another
scale, far outside the brain) are dropped. The meshes are already RAS (x right,
y anterior, z superior, checked: olfactory areas at +y, medulla at -y, left
regions at -x); their unit is the original's own (about 0.1 mm), kept. The
cerebellum is drawn in the surface views too, as in the original's top view.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from brainpainter.atlas.meshfolder import build_mesh_atlas

HERE = Path(__file__).resolve().parent
OUT = HERE / "bp_atlas_mouse" / "data" / "mouse"
CITATION = ("Marinescu RV, Eshaghi A, Alexander DC, Golland P (2019) BrainPainter: A software for the "
            "visualisation of brain structures, biomarkers and associated pathological processes. "
            "arXiv:1905.08627. Mouse meshes from BrainPainter v3 (2021), CC-BY 3.0.")
ATTRIBUTION = """\
The meshes in this folder are derived from BrainPainter, Marinescu et al. (2019), arXiv:1905.08627,
CC-BY 3.0 (https://creativecommons.org/licenses/by/3.0/): the mouse meshes of
https://github.com/razvanmarinescu/brain-coloring (commit 822a7c2), models/Mice_atlas_pial/ and
models/mouse_subcortical_ply/.

The meshes were modified: the PLY triangle soups were welded into indexed meshes (shared vertices),
quads were split into triangles, stored normals were dropped (recomputed when drawn), two stray copies
of the right perirhinal area lying far outside the brain were removed, and the meshes were merged into
the arrays of a brainpainter template (template/*.npz). Made by build_data.py of the
brainpainter-atlas-mouse distribution.
"""


def main(source: str | Path, out: Path = OUT) -> Path:
    """Write the atlas folder `out` from the original's mesh folders in `source`."""
    source = Path(source)
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    build_mesh_atlas(
        "mouse", [source / "Mice_atlas_pial"], subcortical=[source / "mouse_subcortical_ply"],
        orientation="RAS", title="Mouse (BrainPainter 2021)",
        description="The original BrainPainter's mouse brain: 20 cortical areas and 7 structures per "
                    "hemisphere, as meshes (coordinates in the original's own unit, about 0.1 mm).",
        citation=CITATION, surface_also=("Left-Cerebellum", "Right-Cerebellum"), out=out,
        # the views its meshes can show: the hemispheres are open on the medial side
        views=("lateral-left", "subcortical"))
    (out / "ATTRIBUTION.txt").write_text(ATTRIBUTION, encoding="utf-8")
    return out


if __name__ == "__main__":
    default = HERE.parents[3] / "shared" / "data" / "mouse" / "brainpainter2021"
    print("wrote", main(sys.argv[1] if len(sys.argv) > 1 else default))
