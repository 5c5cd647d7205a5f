"""Volumetric label atlases: one smooth, closed mesh per label of a label volume, in a template's space.

``brainpainter atlas add NAME --volume LABELS.nii.gz --lut LUT --space SPACE``
reads an integer label volume (any format nibabel reads) and a look-up table
naming its labels, meshes every label with the subcortical pipeline
(:func:`brainpainter.atlas.meshing.build_structures`: marching cubes,
Taubin smoothing, quadric decimation, volume matched to the voxel volume), and
places the meshes in the template's coordinates. The atlas folder holds
``atlas.json``, ``regions.tsv`` (kind ``subcortical``) and ``subcortical.npz``
(the meshes, same arrays as a template's ``subcortical.npz``); renderers see it
as the template's subcortical part (:meth:`brainpainter.atlas.template.Template.with_volumes`),
drawn in the subcortical views inside the glass brain.

Spaces and the transform into the template
------------------------------------------
The bundled ``fsaverage`` template is in FreeSurfer surface coordinates
(tkr-RAS) of fsaverage. For fsaverage these equal its scanner RAS (the
``vox2ras`` and ``vox2ras-tkr`` of ``fsaverage/mri/*.mgz`` are the same
matrix), and fsaverage's scanner RAS is MNI305 space (its ``talairach.xfm``
is the identity). So:

* ``--space fsaverage`` (MNI305): coordinates are used as they are;
* ``--space MNI152NLin6Asym`` or ``MNI152NLin2009cAsym``: coordinates are
  mapped by FreeSurfer's affine from MNI152 to MNI305 (:data:`MNI152_TO_MNI305`,
  FreeSurfer wiki *CoordinateSystems*, item 8b,
  https://surfer.nmr.mgh.harvard.edu/fswiki/CoordinateSystems, computed from
  ``$FREESURFER_HOME/average/mni152.register.dat``). That registration was made
  for FSL's MNI152 (NLin6Asym); MNI152NLin2009cAsym differs from it by a
  nonlinear warp of a few millimetres, which an affine cannot express. The same
  affine is used for both, and this approximation is recorded in ``atlas.json``.
  For accurate placement (e.g. small nuclei), resample the volume to fsaverage
  (MNI305) first, e.g. with the nonlinear registration of Wu et al. (2018),
  and give ``--space fsaverage``;
* ``--space template``: the volume's world coordinates are already the
  template's (a volume made for that template, such as a template built from
  the volume itself).

Look-up tables
--------------
:func:`read_lut` reads FreeSurfer colour tables (``index name R G B A``, ``#``
comments), BIDS ``dseg.tsv`` (``index``, ``name`` and optional ``color``
columns), CSV files with ``index,name`` (optional header, optional third
column ``#rrggbb``) and plain lists of one name per line (label = line
number, as Tian's ``*_label.txt``). Labels without a colour get one from matplotlib's
``tab20`` cycle. The hemisphere is read from the name (``Left-``, ``lh_``,
``-lh``, ``_L``, ...): ``hippocampus_anterior-lh`` is the left region
``hippocampus_anterior`` (key ``Left-hippocampus_anterior``); the name as
given stays an alias.
"""

from __future__ import annotations

import csv
import json
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshing import Structure, build_structures, merge_structures
from brainpainter.atlas.model import HEMI_PREFIX, SPACES, Region, hemisphere_in_name, write_regions_tsv
from brainpainter.atlas.template import FORMAT, FORMAT_VERSION, Template, load_template
from brainpainter.atlas.user import store_built
from brainpainter.atlas.writer import save_npz
from brainpainter.errors import BrainPainterError, choice_error

#: MNI152 RAS -> MNI305 (fsaverage) RAS, FreeSurfer wiki CoordinateSystems, 8b.
MNI152_TO_MNI305 = np.array([
    [1.0022, 0.0071, -0.0177, 0.0528],
    [-0.0146, 0.9990, 0.0027, -1.5519],
    [0.0129, 0.0094, 1.0027, -1.2012],
    [0.0, 0.0, 0.0, 1.0],
])
#: Templates whose coordinates are MNI305 (FreeSurfer's fsaverage family: tkr-RAS = scanner RAS = MNI305).
MNI305_SUBJECTS = ("fsaverage", "fsaverage6", "fsaverage5", "fsaverage4", "fsaverage3")
VOLUME_FILE = "subcortical.npz"

@dataclass(frozen=True)
class LutEntry:
    """One row of a look-up table: label value, name and colour (None: not given)."""

    index: int
    name: str
    color: tuple[int, int, int] | None = None


def split_hemi(name: str) -> tuple[str, str]:
    """``("lh", "hippocampus_anterior")`` for ``hippocampus_anterior-lh``; ``("bilateral", name)`` else."""
    hemi, rest = hemisphere_in_name(name)
    return hemi or "bilateral", rest


def _hex_color(text: str) -> tuple[int, int, int] | None:
    t = text.strip().lstrip("#")
    if re.fullmatch(r"[0-9a-fA-F]{6}", t):
        return int(t[0:2], 16), int(t[2:4], 16), int(t[4:6], 16)
    return None


def read_lut(path: str | Path) -> list[LutEntry]:
    """Read a look-up table: FreeSurfer colour table, BIDS ``dseg.tsv`` or ``index,name`` CSV.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    list of LutEntry
        In file order; label 0 (background) is left out.

    Raises
    ------
    BrainPainterError
        Missing file, no rows, a row without an integer index, or an index twice.
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise BrainPainterError(f"look-up table {path} does not exist; give a FreeSurfer LUT (.txt), a BIDS "
                                "dseg.tsv or a CSV of index,name")
    text = path.read_text(encoding="utf-8-sig", errors="replace")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise BrainPainterError(f"look-up table {path} has no rows; it needs one row per label (index, name)")
    entries: list[LutEntry] = []
    first = lines[0]
    if "\t" in first and "index" in [c.strip().lower() for c in first.split("\t")]:
        entries = _read_dseg(path, lines)
    elif "," in first or ";" in first:
        entries = _read_csv(path, lines, "," if "," in first else ";")
    elif all(len(ln.split()) == 1 and not re.fullmatch(r"-?\d+", ln.strip()) for ln in lines):
        # one name per line, label = line number (e.g. Tian's Tian_Subcortex_S2_3T_label.txt)
        entries = [LutEntry(i, ln.strip()) for i, ln in enumerate(lines, start=1)]
    else:
        for i, ln in enumerate(lines, start=1):
            parts = ln.split()
            if len(parts) < 2 or not re.fullmatch(r"-?\d+", parts[0]):
                raise BrainPainterError(f"{path} row {i} {ln.strip()[:60]!r} is not 'index name [R G B A]'; "
                                        "a FreeSurfer LUT has an integer, a name and optional colour")
            color = None
            if len(parts) >= 5 and all(re.fullmatch(r"\d+", p) for p in parts[2:5]):
                color = tuple(min(int(p), 255) for p in parts[2:5])
            entries.append(LutEntry(int(parts[0]), parts[1], color))  # type: ignore[arg-type]
    seen: dict[int, str] = {}
    for e in entries:
        if e.index in seen:
            raise BrainPainterError(f"{path} names label {e.index} twice ({seen[e.index]!r}, {e.name!r}); "
                                    "give each label one row")
        seen[e.index] = e.name
    return [e for e in entries if e.index != 0]


def _read_dseg(path: Path, lines: list[str]) -> list[LutEntry]:
    rows = list(csv.DictReader(lines, delimiter="\t"))
    cols = {c.strip().lower(): c for c in rows[0]} if rows else {}
    if "name" not in cols:
        raise BrainPainterError(f"{path} is a BIDS dseg.tsv without a 'name' column; it needs 'index' "
                                "and 'name' (and may have 'color')")
    out = []
    for i, r in enumerate(rows, start=2):
        idx = (r[cols["index"]] or "").strip()
        if not re.fullmatch(r"-?\d+", idx):
            raise BrainPainterError(f"{path} line {i}: index {idx!r} is not an integer")
        color = _hex_color(r[cols["color"]] or "") if "color" in cols else None
        out.append(LutEntry(int(idx), (r[cols["name"]] or "").strip(), color))
    return out


def _read_csv(path: Path, lines: list[str], sep: str) -> list[LutEntry]:
    rows = [[c.strip() for c in row] for row in csv.reader(lines, delimiter=sep)]
    if rows and not re.fullmatch(r"-?\d+", rows[0][0]):
        rows = rows[1:]  # a header
    out = []
    for i, r in enumerate(rows, start=1):
        if len(r) < 2 or not re.fullmatch(r"-?\d+", r[0]) or not r[1]:
            raise BrainPainterError(f"{path} row {i} {sep.join(r)[:60]!r} is not 'index{sep}name'; a CSV "
                                    "look-up table has an integer label and its name per row")
        out.append(LutEntry(int(r[0]), r[1], _hex_color(r[2]) if len(r) > 2 else None))
    return out


def lut_regions(entries: list[LutEntry]) -> list[Region]:
    """Regions (kind ``subcortical``) of LUT entries; hemisphere from the name; colours filled in."""
    import matplotlib

    cycle = matplotlib.colormaps["tab20"].colors  # type: ignore[attr-defined]
    out: list[Region] = []
    keys: dict[str, int] = {}
    for i, e in enumerate(entries):
        hemi, name = split_hemi(e.name)
        rgb = tuple(round(255 * c) for c in cycle[i % len(cycle)][:3])
        color = e.color or cast(tuple[int, int, int], rgb)
        region = Region(e.index, name, hemi, "subcortical", color,
                        () if e.name == HEMI_PREFIX[hemi] + name else (e.name,))
        if region.key in keys:
            raise BrainPainterError(f"labels {keys[region.key]} and {e.index} both name region "
                                    f"{region.key!r}; give each label its own name")
        keys[region.key] = e.index
        out.append(region)
    return out


def space_transform(space: str, template: Template) -> NDArray[Any]:
    """4 x 4 affine from `space` RAS millimetres to the coordinates of `template`.

    Parameters
    ----------
    space : {"MNI152NLin2009cAsym", "MNI152NLin6Asym", "fsaverage", "template"}
    template : brainpainter.atlas.template.Template
    """
    if space not in SPACES:
        raise choice_error("--space", space, SPACES)
    if space == "template":
        return np.eye(4)
    subject = str(template.manifest.get("source", {}).get("subject", template.name))
    if subject not in MNI305_SUBJECTS:
        raise BrainPainterError(
            f"template {template.name!r} (from subject {subject!r}) is not in MNI305/fsaverage space, so a "
            f"{space} volume cannot be placed in it; give a volume in the template's own coordinates with "
            "--space template, or use --template fsaverage")
    return np.eye(4) if space == "fsaverage" else MNI152_TO_MNI305.copy()


@dataclass(frozen=True)
class LabelVolume:
    """An integer label volume and its voxel-to-world affine."""

    data: NDArray[Any]  # int, shape (ni, nj, nk)
    affine: NDArray[Any]  # shape (4, 4)
    source: Path


def read_volume(path: str | Path) -> LabelVolume:
    """Read an integer label volume (NIfTI, MGH, ...) with nibabel; one-line errors for bad input."""
    import nibabel as nib

    from brainpainter.io.hdf5 import check_hdf5
    from brainpainter.io.sniff import HEAD, not_a_volume

    path = Path(path).expanduser()
    if not path.is_file():
        raise BrainPainterError(f"label volume {path} does not exist; give a NIfTI (.nii, .nii.gz) or MGH "
                                "(.mgz) file of integer labels")
    with path.open("rb") as f:
        found = not_a_volume(f.read(HEAD))
    if found:  # never given to nib.load, which reads a GIfTI (and the files it names)
        raise BrainPainterError(f"label volume {path} looks like {found}, not a volume; give a NIfTI (.nii, "
                                ".nii.gz), MGH (.mgz) or MINC file of integer labels")
    check_hdf5(path, "label volume")  # MINC-2 can take its data from other files
    try:
        with warnings.catch_warnings(action="ignore"):  # nibabel's parse warnings: the error says it
            img: Any = nib.load(str(path))
            data = np.asanyarray(img.dataobj)
    except Exception as exc:  # nibabel raises ImageFileError, ValueError, OSError, ...
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise BrainPainterError(f"cannot read {path} as a label volume: {reason}") from None
    data = np.squeeze(data)
    if data.ndim != 3:
        raise BrainPainterError(f"{path} has shape {data.shape}; a label volume is 3-D (one label per voxel)")
    if not np.issubdtype(data.dtype, np.integer):
        # labels saved as floats, sometimes through an 8-bit rescale (0.988, 1.976, ...; 211.27, 212.24,
        # ... with a step under 1), are rounded when no two distinct values round to the same integer;
        # a probability map (many values between two integers) is refused
        values = np.unique(data[np.isfinite(data)])
        rounded = np.rint(values)
        if (len(values) > 65535 or not np.isfinite(data).all()
                or len(np.unique(rounded)) != len(values)):
            raise BrainPainterError(f"{path} holds non-integer values ({data.dtype}); a label volume holds "
                                    "integer labels (a probability map must be thresholded first)")
        data = np.rint(data)
    return LabelVolume(data.astype(np.int64), np.asarray(img.affine, dtype=np.float64), path)


def write_own_template(folder: Path, name: str, volume: str, structures: list[Structure]) -> dict[str, Any]:
    """Write ``folder/template/manifest.json``: a template made only of the volume's meshes (no cortex).

    Its subcortical part is the atlas's ``subcortical.npz``; it has no cortex
    and no glass brain, so only the subcortical views draw it (each framed to
    the meshes): ``subcortical-dorsal``, ``subcortical-left``,
    ``subcortical-ventral``, ``subcortical``.
    """
    points = np.concatenate([s.vertices for s in structures])
    manifest = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "name": name,
        "source": {"subject": name, "volume": volume, "builder": "brainpainter.atlas.volumes"},
        "space": "world coordinates of the label volume (mm, RAS)", "surfaces": ["pial"],
        "labels": {"none": {"source": "no cortical surfaces: a template of volume labels only",
                            "regions": [], "cortex": {}}},
        "subcortical": {"file": f"../{VOLUME_FILE}", "source": volume,
                        "structures": [{"name": s.name, "index": s.index} for s in structures]},
        "glass": {},
        "bounds": {"pial": [points.min(axis=0).round(4).tolist(), points.max(axis=0).round(4).tolist()]},
    }
    (folder / "template").mkdir()
    text = json.dumps(manifest, indent=1) + "\n"
    (folder / "template" / "manifest.json").write_text(text, encoding="utf-8")
    return manifest


def _atlas_json(name: str, vol: LabelVolume, lut: str | Path, space: str, tpl_name: str, label_set: str,
                to_template: NDArray[Any], regions: list[Region], structures: list[Structure], *, title: str,
                description: str, citation: str, own_template: bool) -> dict[str, Any]:
    """The ``atlas.json`` of a volume atlas: where it came from, the transform, each structure's mesh."""
    source_voxel = abs(float(np.linalg.det(vol.affine[:3, :3])))
    return {
        "name": name,
        "title": title or name,
        "kind": "volume",
        "template_labels": label_set,
        "template": tpl_name,
        "description": description or (
            f"Label volume {vol.source.name} ({space}), {len(regions)} structures meshed in template "
            f"{tpl_name!r}" + (" (its own: no cortex)." if own_template else ".")),
        "citation": citation,
        "aliases": [],
        "source": {
            "volume": vol.source.name, "lut": Path(lut).name, "space": space,
            "shape": list(vol.data.shape), "voxel_mm3": round(source_voxel, 6),
            "to_template": to_template.round(6).tolist(),
            "transform_note": {
                "fsaverage": "MNI305 = fsaverage coordinates; used as they are",
                "template": "volume already in the template's coordinates (or a template of its own)",
                "MNI152NLin6Asym": "FreeSurfer's MNI152->MNI305 affine (wiki CoordinateSystems 8b)",
                "MNI152NLin2009cAsym": "FreeSurfer's MNI152->MNI305 affine (wiki CoordinateSystems 8b), made "
                                       "for MNI152NLin6Asym: approximate for 2009cAsym (nonlinear, few mm)",
            }[space],
        },
        "structures": [{
            "name": s.name, "index": s.index, "n_voxels": s.n_voxels, "n_faces": len(s.faces),
            "volume_mm3": round(s.volume_mm3, 3), "voxel_volume_mm3": round(s.voxel_volume_mm3, 3),
            "centroid": [round(float(c), 3) for c in s.vertices.mean(axis=0)], "watertight": s.watertight,
        } for s in structures],
    }


def build_volume_atlas(name: str, volume: str | Path, lut: str | Path, *, space: str = "MNI152NLin2009cAsym",
                       template: str = "fsaverage", title: str = "", description: str = "",
                       citation: str = "", target_fraction: float = 0.3, out: Path,
                       own_template: bool = False,
                       progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Mesh every label of `volume` named in `lut` and write an atlas folder into `out`.

    With `own_template` the volume is a brain of its own (any species, no
    cortical surfaces): the meshes stay in the volume's world coordinates and
    the folder gets a template made of them (:func:`write_own_template`);
    `space` and `template` are then not used.

    Parameters
    ----------
    name : str
    volume, lut : path-like
    space : str
        One of :data:`SPACES`.
    template : str
        Template the meshes are placed in.
    title, description, citation : str
    target_fraction : float
        Faces kept by decimation.
    out : Path
        Existing empty folder.
    progress : callable, optional
        Called with each region key before it is meshed.

    Returns
    -------
    dict
        The ``atlas.json`` written.
    """
    if own_template:
        space, tpl_name, label_set, to_template = "template", name, "none", np.eye(4)
    else:
        tpl = load_template(template)
        to_template = space_transform(space, tpl)
        tpl_name, label_set = tpl.name, ("dk" if "dk" in tpl.label_sets else tpl.label_sets[0])
    vol = read_volume(volume)
    entries = read_lut(lut)
    present = set(np.unique(vol.data).tolist()) - {0}
    named = {e.index for e in entries}
    unnamed = sorted(present - named)
    if unnamed:
        raise BrainPainterError(
            f"{vol.source.name} has labels {unnamed[:8]}{' ...' if len(unnamed) > 8 else ''} that "
            f"{Path(lut).name} does not name; give a look-up table with a row for every label")
    regions = lut_regions([e for e in entries if e.index in present])
    if not regions:
        raise BrainPainterError(f"{vol.source.name} has no label named in {Path(lut).name} (only 0, "
                                "background); give the volume its look-up table")
    vox2world = to_template @ vol.affine
    voxel_volume = abs(float(np.linalg.det(vox2world[:3, :3])))
    structures = build_structures(vol.data, vox2world, voxel_volume, tuple(regions),
                                  target_fraction=target_fraction, progress=progress,
                                  source=vol.source.name)
    save_npz(out / VOLUME_FILE, merge_structures(structures))
    write_regions_tsv(regions, out / "regions.tsv")
    if own_template:
        write_own_template(out, name, vol.source.name, structures)
    meta = _atlas_json(name, vol, lut, space, tpl_name, label_set, to_template, regions, structures,
                       title=title, description=description, citation=citation, own_template=own_template)
    (out / "atlas.json").write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return meta


def add_volume_atlas(name: str, volume: str | Path, lut: str | Path, *, replace: bool = False,
                     out: str | Path | None = None, **kwargs: Any) -> Path:
    """``brainpainter atlas add NAME --volume ... --lut ...``: build and store (or write to `out`)."""
    folder, _ = store_built(name, lambda stage: build_volume_atlas(name, volume, lut, out=stage, **kwargs),
                            replace=replace, out=out)
    return folder
