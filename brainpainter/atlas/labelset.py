"""Label sets for a template made from a per-vertex label map (``.annot`` or GIFTI).

A template's cortex meshes are decimated, but every vertex they keep is a
vertex of the full-resolution FreeSurfer surface (``source_vertex``). A label
map made for that surface (FreeSurfer ``?h.NAME.annot`` or a GIFTI
``.label.gii`` on fsaverage, e.g. the Yeo 2011 networks) therefore gives a
label to every template vertex. No geometry is stored: the new label set is
``vertex_label`` for the vertices of one of the template's own label-set
meshes (the *base*), kept in a label-set overlay folder (``labels.json`` +
``cortex-{hemi}-{name}.npz``, see :mod:`brainpainter.atlas.template`), about 12 kB
per hemisphere for the Yeo networks on fsaverage.

Faces: a face whose three vertices share a label gets that label. A face whose
vertices differ is split when the mesh is loaded (:func:`split_mesh`,
"marching triangles"): the boundary crosses each label-crossing edge once
(and runs through the face's centroid when all three labels differ). The
crossing point is shared by both faces on that edge, so the mesh stays
closed, without T-junctions. Where on the edge it lies comes from
:func:`smooth_crossings`: the zero of the difference of the two labels'
indicator functions after a few steps of mesh smoothing, i.e. the boundary
is the iso-line of a smoothed label map, not the zigzag through edge
midpoints (or the staircase of whole triangles) that vertex labels alone
give. The same code splits the built-in atlases (their template files carry
``vertex_label``) and the label sets added from label maps (overlays).

Which base: all label-set meshes of a template have about the same vertex
count, but each keeps its own region boundaries at full resolution. The base
chosen is the one whose triangles straddle the new label boundaries least
(smallest pial area of faces whose three vertices do not share one label). On
the bundled fsaverage every Yeo 7-network region comes out within 0.5 % of its
full-resolution pial area.

Validation: a label map must have exactly one label per vertex of the surface
the template was built from. That count is read from the template manifest
(``n_source_vertices``, or derived from ``n_source_faces`` as ``F / 2 + 2``,
true for the closed, genus-0 triangulations FreeSurfer makes); it is never
guessed from the vertices the template happens to keep.
"""

from __future__ import annotations

import json
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas import registry
from brainpainter.atlas.mesh import faces_digest, smooth_crossings, split_faces
from brainpainter.atlas.model import HEMI_PREFIX, Region, write_regions_tsv
from brainpainter.atlas.template import FORMAT_VERSION, HEMIS, LABELS_FILE, LABELS_FORMAT, Template
from brainpainter.atlas.writer import save_npz
from brainpainter.errors import BrainPainterError
from brainpainter.io.files import check_input
from brainpainter.io.rawtable import has_control

#: Colour-table names that are not regions (compared in lower case), besides any "medial ... wall".
NON_REGION_NAMES = frozenset({"", "unknown", "???", "corpuscallosum", "medial_wall", "medial.wall"})
LABEL_SUFFIXES = (".annot", ".label.gii", ".gii", ".label.gii.gz", ".gii.gz")


def is_non_region(name: str) -> bool:
    """True for colour-table entries such as ``unknown``, ``???`` or ``FreeSurfer_Defined_Medial_Wall``."""
    n = str(name).strip().lower()
    return n in NON_REGION_NAMES or ("medial" in n and "wall" in n)


@dataclass(frozen=True)
class LabelMap:
    """Labels of one hemisphere's full-resolution vertices, as read from a label map
    (FreeSurfer ``.annot`` or GIFTI ``.label.gii``) by :func:`read_label_map`.

    Attributes
    ----------
    hemi : {"lh", "rh"}
    source : Path
    labels : ndarray of int64, shape (n_vertices,)
        Index into `names`; never -1 (unlabelled vertices get a non-region name).
    names : tuple of str
        Colour-table names.
    colors : ndarray of uint8, shape (n_names, 3)
        Colour-table colours.
    """

    hemi: str
    source: Path
    labels: NDArray[Any]
    names: tuple[str, ...]
    colors: NDArray[Any]


def hemi_of(path: str | Path) -> str | None:
    """Hemisphere named by a label-map file name (``lh.x.annot``, ``x.L.label.gii``, ``hemi-R``)."""
    name = Path(path).name
    low = name.lower()
    if low.startswith(("lh.", "lh_")) or "hemi-l_" in low or "hemi-l." in low or ".l." in low:
        return "lh"
    if low.startswith(("rh.", "rh_")) or "hemi-r_" in low or "hemi-r." in low or ".r." in low:
        return "rh"
    return None


def read_label_map(path: str | Path, hemi: str) -> LabelMap:
    """Read a FreeSurfer ``.annot`` or a GIFTI label file (``.label.gii``).

    Parameters
    ----------
    path : path-like
    hemi : {"lh", "rh"}

    Raises
    ------
    BrainPainterError
        Missing or unreadable file, or no colour table.
    """
    path = Path(path).expanduser()
    check_input(path, "label map", hint="give a FreeSurfer .annot or a GIFTI .label.gii file made for the "
                                        "template's surface")
    low = path.name.lower()
    if not low.endswith(LABEL_SUFFIXES):
        raise BrainPainterError(f"label map {path} must be a FreeSurfer .annot or a GIFTI .label.gii file "
                                f"(allowed endings: {list(LABEL_SUFFIXES)})")
    named = hemi_of(path)
    if named is not None and named != hemi:
        raise _swapped(path, hemi, named, "its file name")
    try:
        with warnings.catch_warnings(action="ignore"):  # nibabel's parse warnings: the error says it
            if low.endswith(".annot"):
                from nibabel.freesurfer import read_annot  # type: ignore[attr-defined]

                labels, ctab, raw_names = read_annot(str(path))  # type: ignore[no-untyped-call]
                names = [n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n) for n in raw_names]
                colors = np.asarray(ctab, dtype=np.int64)[:, :3]
                labels = np.asarray(labels, dtype=np.int64)
            else:
                labels, names, colors = _read_gifti_labels(path, hemi)
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel raises ValueError, struct.error, OSError, ExpatError...
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise BrainPainterError(f"cannot read {path} as a label map: {reason}") from None
    return label_map(hemi, path, labels, list(names), colors)


def label_map(hemi: str, path: Path, labels: NDArray[Any], names: list[str], colors: NDArray[Any]
              ) -> LabelMap:
    """A checked :class:`LabelMap`: `labels` (n,) index `names` (-1: none), `colors` (len(names), 3) 0-255."""
    if not names:
        raise BrainPainterError(f"{path} has no colour table, so it names no regions; give a label map "
                                "whose colour table names its regions")
    bad = next((n for n in names if has_control(n)), None)
    if bad is not None:
        raise BrainPainterError(f"{path}: the region name {bad[:40]!r} contains control or text-direction "
                                "characters; names may hold letters, digits, spaces and punctuation only")
    folded: dict[str, str] = {}
    for n in (n for n in names if not is_non_region(n)):
        if (other := folded.setdefault(n.strip().casefold(), n)) != n:
            raise BrainPainterError(
                f"{path}: the region names {other!r} and {n!r} differ only in case, so brainpainter (which "
                "matches region names ignoring case) cannot keep them apart; rename one in the colour table"
            )
    if (labels < 0).any():  # vertices outside the colour table: a non-region entry
        fill = next((i for i, n in enumerate(names) if is_non_region(n)), None)
        if fill is None:
            fill = len(names)
            names.append("unknown")
            colors = np.vstack([colors, [[25, 5, 25]]])
        labels = np.where(labels < 0, fill, labels)
    return LabelMap(hemi, path, labels, tuple(names), np.asarray(colors).clip(0, 255).astype(np.uint8))


def _swapped(path: Path, hemi: str, named: str, how: str) -> BrainPainterError:
    side = {"lh": "left", "rh": "right"}
    return BrainPainterError(
        f"label map {path} is given for the {side[hemi]} hemisphere ({hemi}=...), but {how} says "
        f"{side[named]}; swap the files (--annot {named}={path.name}), or rename the file if it is right")


def _read_gifti_labels(path: Path, hemi: str | None = None) -> tuple[NDArray[Any], list[str], NDArray[Any]]:
    from brainpainter.io.gifti import read_gifti

    img: Any = read_gifti(path, what="label map")
    if not getattr(img, "darrays", None):
        raise BrainPainterError(f"{path} holds no data array; a GIFTI label file has one label per vertex")
    meta = {**dict(img.meta or {}), **dict(img.darrays[0].meta or {})}
    structure = str(meta.get("AnatomicalStructurePrimary", "")).lower()
    side = "lh" if structure.endswith("left") else "rh" if structure.endswith("right") else None
    given = hemi_of(path) if hemi is None else hemi
    if side is not None and given is not None and side != given:
        raise _swapped(path, given, side, f"its AnatomicalStructurePrimary ({structure!r})")
    keys = np.asarray(img.darrays[0].data).astype(np.int64).ravel()
    table = list(img.labeltable.labels)
    names = [str(lab.label) for lab in table]
    colors = np.array([[round(255 * float(c if c is not None else 0)) for c in (lab.red, lab.green, lab.blue)]
                       for lab in table], dtype=np.int64).reshape(-1, 3)
    order = {int(lab.key): i for i, lab in enumerate(table)}
    lookup = np.vectorize(lambda k: order.get(int(k), -1), otypes=[np.int64])
    return (lookup(keys) if len(keys) else keys), names, colors


def source_vertex_count(template: Template, hemi: str) -> int:
    """Vertices of the full-resolution surface `hemi` of `template` was built from.

    Read from the manifest entries the builder writes (``n_source_vertices``,
    or ``n_source_faces``: a closed genus-0 triangulation has ``F / 2 + 2``
    vertices); a full-resolution template (``source_vertex`` is
    ``0..n-1``) counts its own vertices.
    """
    counts: dict[int, str] = {}
    for name in template.label_sets:
        entry = template.manifest["labels"][name].get("cortex", {}).get(hemi, {})
        if "base" in entry or not entry:
            continue
        if "n_source_vertices" in entry:
            counts.setdefault(int(entry["n_source_vertices"]), name)
        elif "n_source_faces" in entry:
            counts.setdefault(int(entry["n_source_faces"]) // 2 + 2, name)
        else:
            sv = template.base_cortex(name, hemi).source_vertex
            if np.array_equal(sv, np.arange(len(sv))):
                counts.setdefault(len(sv), name)
    if len(counts) != 1:
        raise BrainPainterError(
            f"template {template.name!r} does not record one source-surface size for {hemi} "
            f"(found {sorted(counts) or 'none'}); rebuild it with 'brainpainter template build'"
        )
    return next(iter(counts))


def check_vertex_count(template: Template, label_map: LabelMap) -> None:
    """One-line error unless `label_map` has one label per source-surface vertex."""
    expected = source_vertex_count(template, label_map.hemi)
    n = len(label_map.labels)
    if n != expected:
        subject = template.manifest.get("source", {}).get("subject", template.name)
        raise BrainPainterError(
            f"{label_map.source} labels {n} vertices, but template {template.name!r} needs a "
            f"{label_map.hemi} label map with {expected} (one per vertex of {subject}'s {label_map.hemi} "
            f"surface); give the file made for {subject}, or a template built from your surface "
            "(--template)"
        )


def _straddle_area(template: Template, base: str, maps: dict[str, LabelMap]) -> float:
    """Pial area of `base` faces whose three vertices do not share one label."""
    total = 0.0
    for hemi, m in maps.items():
        cm = template.base_cortex(base, hemi)
        lab = m.labels[cm.source_vertex][cm.faces]
        mixed = ~((lab[:, 0] == lab[:, 1]) & (lab[:, 1] == lab[:, 2]))
        v = cm.vertices.get("pial", next(iter(cm.vertices.values()))).astype(np.float64)
        f = cm.faces[mixed]
        total += 0.5 * float(np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                                            axis=1).sum())
    return total


def base_label_sets(template: Template) -> list[str]:
    """Label sets of `template` with their own meshes (not overlays)."""
    return [n for n in template.label_sets
            if all("base" not in e for e in template.manifest["labels"][n].get("cortex", {}).values())]


def choose_base(template: Template, maps: dict[str, LabelMap]) -> str:
    """The template label set whose mesh straddles the boundaries of `maps` least."""
    candidates = base_label_sets(template)
    if not candidates:
        raise BrainPainterError(f"template {template.name!r} has no cortex label set to label")
    return min(candidates, key=lambda b: (_straddle_area(template, b, maps), b))


@dataclass(frozen=True)
class HemiLabels:
    """A new label set on one hemisphere: names, a label per base-mesh vertex, the faces it makes."""

    hemi: str
    vertex_label: NDArray[Any]  # int16, shape (n_base_vertices,)
    face_label: NDArray[Any]  # int16, shape (n_faces after splitting,)
    names: tuple[str, ...]
    colors: NDArray[Any]  # uint8, shape (n_names, 3)
    source: str
    source_label: NDArray[Any] | None = None  # int16, shape (n_source_vertices,): the whole label map

    def region_faces(self) -> dict[str, int]:
        counts = np.bincount(self.face_label.astype(np.int64), minlength=len(self.names))
        return {n: int(counts[i]) for i, n in enumerate(self.names) if counts[i]}

    def regions(self) -> list[tuple[int, str, tuple[int, int, int]]]:
        """(colour-table index, name, colour) of the regions with faces, in colour-table order."""
        used = set(np.unique(self.face_label).tolist())
        return [(i, n, (int(self.colors[i][0]), int(self.colors[i][1]), int(self.colors[i][2])))
                for i, n in enumerate(self.names) if i in used and not is_non_region(n)]


@dataclass(frozen=True)
class LabelSet:
    """A label set made for a template from label maps.

    Attributes
    ----------
    name : str
    template : str
    base : str
        Template label set whose meshes the labels are for.
    hemis : dict of str to HemiLabels
    too_small : dict of str to list of str
        Per hemisphere, regions of the label map with vertices but no whole
        face on the template mesh (left out).
    """

    name: str
    template: str
    base: str
    hemis: dict[str, HemiLabels]
    too_small: dict[str, list[str]] = field(default_factory=dict)


def build_label_set(name: str, template: Template, maps: dict[str, LabelMap],
                    base: str | None = None) -> LabelSet:
    """Label the faces of a template mesh by per-vertex label maps (one per hemisphere).

    Parameters
    ----------
    name : str
        Name of the new label set.
    template : Template
    maps : dict of {"lh", "rh"} to LabelMap
        Both hemispheres.
    base : str, optional
        Template label set to label (default: :func:`choose_base`).
    """
    missing = [h for h in HEMIS if h not in maps]
    if missing:
        raise BrainPainterError(f"a label map for each hemisphere is needed; {missing} is missing "
                                "(give --annot lh=FILE --annot rh=FILE)")
    for m in maps.values():
        check_vertex_count(template, m)
    base = base or choose_base(template, maps)
    hemis: dict[str, HemiLabels] = {}
    too_small: dict[str, list[str]] = {}
    for hemi in HEMIS:
        m = maps[hemi]
        cm = template.base_cortex(base, hemi)
        if len(m.names) > np.iinfo(np.int16).max:
            raise BrainPainterError(f"{m.source} has {len(m.names)} colour-table entries; at most 32767")
        vertex_label = m.labels[cm.source_vertex].astype(np.int16)
        face_label = split_faces(cm.faces, vertex_label)[1]
        hl = HemiLabels(hemi, vertex_label, face_label.astype(np.int16), m.names, m.colors, m.source.name,
                        m.labels.astype(np.int16))
        hemis[hemi] = hl
        with_vertices = {m.names[i] for i in np.unique(m.labels).tolist() if not is_non_region(m.names[i])}
        too_small[hemi] = sorted(with_vertices - {n for _, n, _ in hl.regions()})
    if not any(h.regions() for h in hemis.values()):
        raise BrainPainterError(
            f"the label maps {[m.source.name for m in maps.values()]} name no region on template "
            f"{template.name!r} (only entries such as unknown or medial wall); give a label map with regions"
        )
    return LabelSet(name, template.name, base, hemis, too_small)


def _hex(rgb: Sequence[int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*(int(c) for c in rgb[:3]))


def write_label_set(folder: Path, label_set: LabelSet, template: Template, *,
                    per_source_vertex: bool = False) -> dict[str, Any]:
    """Write ``labels.json`` and ``cortex-{hemi}-{name}.npz`` into `folder`; returns the JSON.

    With `per_source_vertex` the files hold the whole label map (``source_label``,
    one per full-resolution vertex) instead of the labels of the base mesh's
    vertices: a little larger, but it fits the template after a rebuild.
    """
    where = "full-resolution vertices (mapped to" if per_source_vertex else "vertices of"
    entry: dict[str, Any] = {"source": ", ".join(label_set.hemis[h].source for h in HEMIS),
                   "method": f"label map at the {where} the template's {label_set.base!r} meshes"
                             f"{')' if per_source_vertex else ''}; faces with several labels split "
                             "through edge midpoints",
                   "regions": [], "cortex": {}}
    for hemi in HEMIS:
        hl = label_set.hemis[hemi]
        for _, n, _ in hl.regions():
            if n not in entry["regions"]:
                entry["regions"].append(n)
        file = f"cortex-{hemi}-{label_set.name}.npz"
        base = template.base_cortex(label_set.base, hemi)
        if per_source_vertex and hl.source_label is not None:
            save_npz(folder / file, {"source_label": hl.source_label})
            guard = {}
        else:
            crossing = smooth_crossings(base.faces, hl.vertex_label).astype(np.float32)
            save_npz(folder / file, {"vertex_label": hl.vertex_label, "boundary_t": crossing})
            guard = {"base_faces_sha256": faces_digest(base.faces)}
        entry["cortex"][hemi] = {
            "file": file, "base": label_set.base, **guard,
            "names": list(hl.names), "colors": [_hex(c) for c in hl.colors],
            "n_base_vertices": len(base.source_vertex), "n_faces": len(hl.face_label),
            "n_source_vertices": source_vertex_count(template, hemi),
            "region_faces": hl.region_faces(),
        }
    meta = {"format": LABELS_FORMAT, "format_version": FORMAT_VERSION, "template": template.name,
            "labels": {label_set.name: entry}}
    (folder / LABELS_FILE).write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return meta


def atlas_regions(label_set: LabelSet, region_aliases: dict[str, tuple[str, ...]] | None = None,
                  subcortical: tuple[Region, ...] = ()) -> list[Region]:
    """Regions of an atlas drawn with `label_set`: cortical per hemisphere, then `subcortical`.

    Indices follow FreeSurfer's ``ctx-lh-*`` look-up-table convention: 1000
    (left) or 2000 (right) plus the colour-table index.
    """
    region_aliases = region_aliases or {}
    out: list[Region] = []
    for hemi, offset in (("lh", 1000), ("rh", 2000)):
        for i, n, color in label_set.hemis[hemi].regions():
            aliases = (f"ctx-{hemi}-{n}", *region_aliases.get(n, ()))
            out.append(Region(offset + i, n, hemi, "cortical", color, aliases))
    keys = {r.key for r in out}
    out.extend(r for r in subcortical if r.key not in keys)
    return out


def template_subcortical(template: Template) -> tuple[Region, ...]:
    """Subcortical regions of the built-in look-up table that `template` has meshes for."""
    names = {s["name"] for s in template.manifest.get("subcortical", {}).get("structures", [])}
    try:
        rows = registry.atlases.get("dk").subcortical()
    except BrainPainterError:
        return ()
    return tuple(r for r in rows if r.key in names)


_PART_B = re.compile(r"^PART B", re.MULTILINE)


def write_license(folder: Path, template: Template, sources: list[str]) -> bool:
    """Write ``LICENSE.FreeSurfer.txt`` for data derived from a FreeSurfer template (if it has one)."""
    lic = template.path / "LICENSE.FreeSurfer.txt"
    if not lic.is_file():
        return False
    text = lic.read_text(encoding="utf-8")
    head = text.split("\n\n", 1)[0]
    match = _PART_B.search(text)
    body = text[match.start():] if match else ""
    notice = "\n".join([
        "The label files in this directory (cortex-*.npz, labels.json, regions.tsv) are data",
        "derived (modified) from the label maps",
        *(f"  {s}" for s in sources),
        f"and from the brainpainter template {template.name!r}, itself data derived (modified) from",
        "FreeSurfer: " + str(template.manifest.get("attribution", "")).strip(),
        "They are not endorsed by MGH. Research use; see the licence below.",
        "",
    ])
    (folder / "LICENSE.FreeSurfer.txt").write_text(f"{head}\n\n{notice}\n{body}", encoding="utf-8")
    return True


def write_atlas_folder(folder: Path, label_set: LabelSet, template: Template, *, title: str = "",
                       description: str = "", citation: str = "", aliases: tuple[str, ...] = (),
                       region_aliases: dict[str, tuple[str, ...]] | None = None,
                       subcortical: bool = True, extra: dict[str, Any] | None = None,
                       per_source_vertex: bool = False) -> None:
    """Write a complete atlas folder (``atlas.json``, ``regions.tsv``, overlay, licence) into `folder`.

    The folder loads with :func:`brainpainter.atlas.model.load_atlas_dir`; it is what
    ``brainpainter atlas add`` stores and what an atlas plugin ships.
    """
    folder.mkdir(parents=True, exist_ok=True)
    write_label_set(folder, label_set, template, per_source_vertex=per_source_vertex)
    sub = template_subcortical(template) if subcortical else ()
    regions = atlas_regions(label_set, region_aliases, sub)
    write_regions_tsv(regions, folder / "regions.tsv")
    sources = [label_set.hemis[h].source for h in HEMIS]
    n = {h: sum(1 for r in regions if r.hemi == h and r.kind == "cortical") for h in HEMIS}
    meta = {
        "name": label_set.name,
        "title": title or label_set.name,
        "template_labels": label_set.name,
        "template": template.name,
        "description": description or (
            f"Label map {' + '.join(sources)} on template {template.name!r}: {n['lh']} left and "
            f"{n['rh']} right cortical regions{', plus aseg subcortical structures' if sub else ''}."),
        "citation": citation,
        "aliases": list(aliases),
        "source": {"label_maps": sources, "base_label_set": label_set.base,
                   "too_small": {h: v for h, v in label_set.too_small.items() if v}, **(extra or {})},
    }
    (folder / "atlas.json").write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    write_license(folder, template, sources)


def region_keys(label_set: LabelSet) -> list[str]:
    """Cortical region keys (``Left-7Networks_1``...) of a label set."""
    return [HEMI_PREFIX[h] + n for h in HEMIS for _, n, _ in label_set.hemis[h].regions()]
