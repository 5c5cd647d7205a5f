"""Atlas look-up tables (``regions.tsv``) made from a built template.

Cortical rows come from the colour tables that the builder copied into the
template manifest (annotation or GCSA colour tables): one row per region and
hemisphere, ``index`` = FreeSurferColorLUT index, colour from the colour
table, and the FreeSurferColorLUT name as alias. Non-regions (``unknown``,
``corpuscallosum``, ``Unknown``, ``Medial_wall``) and colour-table entries
no vertex carries (DKT has no banks of the STS, frontal or temporal pole)
are left out. Subcortical rows are the bundled ``aseg.tsv``
(FreeSurferColorLUT rows, copied as ``aseg.tsv`` next to the atlases).

FreeSurferColorLUT numbering:

- DK and DKT (``aparc``, ``aparc.DKTatlas``): ``ctx-lh-<name>`` = 1000 + i,
  ``ctx-rh-<name>`` = 2000 + i, with i the position of the name in the DK
  colour table (``bankssts`` = 1001 ... ``insula`` = 1035);
- Destrieux (``aparc.a2009s``): ``ctx_lh_<name>`` = 11100 + i,
  ``ctx_rh_<name>`` = 12100 + i, with i the position in its colour table.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from brainpainter.atlas.model import Region, write_regions_tsv
from brainpainter.errors import BrainPainterError
from brainpainter_builder.subcortical import aseg_table_path

#: label set -> (label set whose colour table numbers it, lh base, rh base, LUT name pattern)
LUT_NUMBERING = {
    "dk": ("dk", 1000, 2000, "ctx-{hemi}-{name}"),
    "dkt": ("dk", 1000, 2000, "ctx-{hemi}-{name}"),
    "destrieux": ("destrieux", 11100, 12100, "ctx_{hemi}_{name}"),
}


def _rgb(hex_colour: str) -> tuple[int, int, int]:
    h = hex_colour.lstrip("#")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)


def cortical_regions(manifest: dict[str, Any], label_set: str) -> list[Region]:
    """Cortical rows of `label_set` (lh rows, then rh rows, in colour-table order)."""
    if label_set not in LUT_NUMBERING:
        raise BrainPainterError(f"no FreeSurferColorLUT numbering known for label set {label_set!r}; "
                                f"known: {sorted(LUT_NUMBERING)}")
    ref_set, lh_base, rh_base, pattern = LUT_NUMBERING[label_set]
    labels = manifest["labels"]
    for needed in (label_set, ref_set):
        if needed not in labels:
            raise BrainPainterError(
                f"template {manifest.get('name')!r} has no label set {needed!r}, needed for the "
                f"{label_set!r} table; it has {sorted(labels)}")
    regions = []
    for hemi, base in (("lh", lh_base), ("rh", rh_base)):
        entry = labels[label_set]["cortex"][hemi]
        ref_names = labels[ref_set]["cortex"][hemi]["names"]
        colours = dict(zip(entry["names"], entry["colors"], strict=True))
        for name in labels[label_set]["regions"]:
            if name not in ref_names:
                raise BrainPainterError(
                    f"region {name!r} of {label_set!r} is not in the {ref_set!r} colour table, "
                    "so it has no FreeSurferColorLUT index")
            regions.append(Region(
                index=base + ref_names.index(name), name=name, hemi=hemi, kind="cortical",
                color=_rgb(colours[name]), aliases=(pattern.format(hemi=hemi, name=name),)))
    return regions


def write_atlas_tables(template_dir: str | Path, data_dir: str | Path,
                       label_sets: tuple[str, ...] = ("dk", "destrieux", "dkt")) -> list[Path]:
    """Write ``data_dir/<set>/regions.tsv`` for each label set and ``data_dir/aseg.tsv``.

    Parameters
    ----------
    template_dir : path-like
        A built template (its ``manifest.json`` holds names and colours).
    data_dir : path-like
        The atlas data folder (``plugins/atlases/brainpainter_atlases/data``).

    Returns
    -------
    list of Path
        Files written.
    """
    manifest = json.loads((Path(template_dir) / "manifest.json").read_text(encoding="utf-8"))
    data_dir = Path(data_dir)
    written = []
    for label_set in label_sets:
        rows = cortical_regions(manifest, label_set)
        out = data_dir / label_set / "regions.tsv"
        out.parent.mkdir(parents=True, exist_ok=True)
        write_regions_tsv(rows, out)
        written.append(out)
    aseg = data_dir / "aseg.tsv"
    shutil.copyfile(aseg_table_path(), aseg)
    written.append(aseg)
    return written
