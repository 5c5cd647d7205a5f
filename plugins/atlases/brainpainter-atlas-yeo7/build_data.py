"""Make bp_atlas_yeo7/data/yeo7 from FreeSurfer's Yeo 2011 annotations.

    python build_data.py /path/to/freesurfer/subjects/fsaverage

Uses the same code as ``brainpainter atlas add NAME --annot ... --out DIR``,
with the network names as region aliases. Only derived data is written (one
label per vertex of the template's cortex mesh, colours and names); the
annotation files themselves are not copied.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from brainpainter.atlas.user import add_label_map

HERE = Path(__file__).resolve().parent
OUT = HERE / "bp_atlas_yeo7" / "data" / "yeo7"

#: Network names used by Yeo et al. (2011) and by the Schaefer parcellations' labels.
NETWORKS = {
    "7Networks_1": ("Visual", "Vis"),
    "7Networks_2": ("Somatomotor", "SomMot"),
    "7Networks_3": ("DorsalAttention", "DorsAttn"),
    "7Networks_4": ("VentralAttention", "SalVentAttn"),
    "7Networks_5": ("Limbic",),
    "7Networks_6": ("Frontoparietal", "Cont"),
    "7Networks_7": ("Default",),
}
CITATION = (
    "Yeo BTT, Krienen FM, Sepulcre J, Sabuncu MR, Lashkari D, Hollinshead M, Roffman JL, Smoller JW, "
    "Zollei L, Polimeni JR, Fischl B, Liu H, Buckner RL (2011) The organization of the human cerebral "
    "cortex estimated by intrinsic functional connectivity. J Neurophysiol 106(3):1125-1165."
)


def main(subject_dir: str | Path, out: Path = OUT) -> Path:
    """Write the atlas folder `out` from ``SUBJECT/label/?h.Yeo2011_7Networks_N1000.annot``."""
    label = Path(subject_dir) / "label"
    if out.exists():
        shutil.rmtree(out)
    add_label_map(
        "yeo7",
        {h: label / f"{h}.Yeo2011_7Networks_N1000.annot" for h in ("lh", "rh")},
        template="fsaverage",
        title="Yeo 2011 7 networks",
        description="Yeo et al. (2011) 7 resting-state networks (liberal cortex mask, N=1000) on "
                    "fsaverage, 7 per hemisphere, plus FreeSurfer aseg subcortical structures.",
        citation=CITATION,
        region_aliases=NETWORKS,
        out=out,
    )
    return out


if __name__ == "__main__":
    default = HERE.parents[3] / "shared" / "data" / "freesurfer" / "subjects" / "fsaverage"
    print("wrote", main(sys.argv[1] if len(sys.argv) > 1 else default))
