"""Mesh-folder atlases: a folder of region meshes (a file per region) becomes an atlas with its own brain.

``brainpainter atlas add NAME --meshes DIR [--subcortical-meshes DIR2]``
reads every mesh file of DIR (OBJ, PLY ASCII or binary, STL, OFF, GLB/glTF
through trimesh; GIfTI surfaces ``*.surf.gii``/``*.gii`` through nibabel)
and makes one region per file:

* the **hemisphere** comes from the name (``lh.``/``rh.``, ``Left-``/``Right-``,
  ``_L``/``_R``, ``left_``/``right_``: :func:`brainpainter.atlas.volumes.split_hemi`);
  a name without one is a bilateral (midline) region. A prefix that every
  file of a folder shares after the hemisphere (``pial.Mice.`` in
  ``lh.pial.Mice.Auditory.ply``) is dropped, so that file is region
  ``Left-Auditory``; the file name stays an alias. ``--names FILE`` (CSV
  ``file,name[,aliases...]``) names regions explicitly;
* regions of DIR with a hemisphere are the **outer surface** (the template's
  cortex of that hemisphere, drawn in the lateral, dorsal, ... views and as
  the glass brain); regions of DIR without one and all regions of DIR2 are
  **structures** drawn in the subcortical views inside the glass brain. A
  brain without one of the two parts draws the other in every view
  (:meth:`brainpainter.rendering.geometry.SceneGeometry.visible`).

Each mesh is **welded** (triangle soups, where every face has its own three
vertices as exported by Blender's PLY writer, share their vertices again:
``trimesh`` ``merge_vertices``, ignoring stored normals), polygons are
fan-triangulated, and closed meshes are wound outwards. Normals are not
stored: every renderer gets them from
:func:`brainpainter.rendering.geometry.vertex_normals`, the project's one
normals function, from the welded faces. Checks, per mesh: no faces, or
non-finite coordinates -> one-line error; connected pieces lying far outside
all the other meshes (:data:`STRAY_RADII` times the brain's radius from its
centre, e.g. a copy of a region exported at another scale) are dropped;
more than :data:`MAX_FACES` faces -> decimated (MeshLab quadric edge
collapse); each is reported as a note.

Units and orientation are never silently assumed: ``--units`` (mm, um, cm, m)
scales to millimetres and ``--orientation`` (three letters, the direction
each axis *increases* towards, nibabel's convention: ``RAS``, ``LPS``,
``PIL``...) turns the axes into RAS (x right, y anterior, z superior), the
frame every view uses. Not given, the coordinates are kept as they are and
the report says so, with the extent and a check of the left/right axis from
the regions' names (left regions should lie at negative x). Note that
BrainGlobe's orientation names the *origin* corner (``asr``: from anterior,
superior, right), which is ``PIL`` here.

The atlas folder holds ``atlas.json``, ``regions.tsv`` and ``template/`` (a
template made of the meshes: ``manifest.json``, ``cortex-{hemi}.npz`` (also the
glass brain), ``subcortical.npz``), used whenever the atlas is
rendered without another template (:attr:`brainpainter.atlas.model.Atlas.template_dir`).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshfiles import mesh_files, mesh_stem, orientation_matrix, read_mesh, weld
from brainpainter.atlas.model import HEMI_PREFIX, Region, write_regions_tsv
from brainpainter.atlas.template import FORMAT, FORMAT_VERSION
from brainpainter.atlas.user import store_built
from brainpainter.atlas.volumes import split_hemi
from brainpainter.atlas.writer import save_npz
from brainpainter.errors import BrainPainterError, choice_error

#: Meshes with more faces are decimated to this many.
MAX_FACES = 200_000
#: Connected pieces whose centre lies further than this many brain radii from the brain's centre are dropped.
STRAY_RADII = 4.0
#: Millimetres per unit.
UNITS = {"mm": 1.0, "um": 1e-3, "cm": 10.0, "m": 1e3}


@dataclass
class RegionMesh:
    """One region's mesh as read and checked.

    Attributes
    ----------
    file : Path
    name : str
        Region name without hemisphere.
    hemi : {"lh", "rh", "bilateral"}
    part : {"surface", "structure"}
        Outer surface (cortex of `hemi`) or a structure of the subcortical views.
    vertices : ndarray of float64, shape (n_vertices, 3)
    faces : ndarray of int64, shape (n_faces, 3)
    aliases : tuple of str
    notes : list of str
        What was changed (welded, pieces dropped, decimated).
    n_read_vertices : int
        Vertices in the file (before welding).
    """

    file: Path
    name: str
    hemi: str
    part: str
    vertices: NDArray[Any]
    faces: NDArray[Any]
    aliases: tuple[str, ...] = ()
    notes: list[str] = field(default_factory=list)
    n_read_vertices: int = 0

    @property
    def key(self) -> str:
        return HEMI_PREFIX[self.hemi] + self.name


# -- names ----------------------------------------------------------------------------
def read_names(path: str | Path) -> dict[str, tuple[str, tuple[str, ...]]]:
    """``--names FILE``: CSV/TSV rows ``file,name[,alias,...]`` -> {file stem: (name, aliases)}.

    `file` is a file name with or without its ending; `name` is the region
    name (``Left-Auditory``: the hemisphere is read from it). A header row
    starting with ``file`` is skipped.
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise BrainPainterError(f"names file {path} does not exist; give a CSV of file,name[,aliases]")
    text = path.read_text(encoding="utf-8-sig")
    sep = "\t" if "\t" in text.splitlines()[0] else ","
    out: dict[str, tuple[str, tuple[str, ...]]] = {}
    for i, row in enumerate(csv.reader(text.splitlines(), delimiter=sep), start=1):
        row = [c.strip() for c in row]
        if not row or not row[0] or row[0].startswith("#") or (i == 1 and row[0].lower() == "file"):
            continue
        if len(row) < 2 or not row[1]:
            raise BrainPainterError(f"{path} row {i} {sep.join(row)[:60]!r} is not "
                                    f"'file{sep}name[{sep}alias...]'")
        out[mesh_stem(Path(row[0]))] = (row[1], tuple(a for a in row[2:] if a))
    return out


def _common_prefix(names: list[str]) -> str:
    """The ``.``/``-``/``_``-ended prefix every name shares (leaving each name non-empty)."""
    if len(names) < 2:
        return ""
    prefix = names[0]
    for n in names[1:]:
        while not n.startswith(prefix):
            prefix = prefix[:-1]
    cut = max(prefix.rfind(c) for c in ".-_ ")
    prefix = prefix[: cut + 1] if cut >= 0 else ""
    return prefix if all(len(n) > len(prefix) for n in names) else ""


def name_regions(files: list[Path], names: Mapping[str, tuple[str, tuple[str, ...]]]
                 ) -> list[tuple[Path, str, str, tuple[str, ...]]]:
    """(file, hemi, name, aliases) per file: from `names`, else from the file name."""
    split = {f: split_hemi(mesh_stem(f)) for f in files}
    prefix = _common_prefix([split[f][1] for f in files if mesh_stem(f) not in names])
    out = []
    for f in files:
        stem = mesh_stem(f)
        if stem in names:
            given, aliases = names[stem]
            hemi, name = split_hemi(given)
            out.append((f, hemi, name, tuple(dict.fromkeys((*aliases, stem)))))
        else:
            hemi, name = split[f]
            out.append((f, hemi, name[len(prefix):], (stem,)))
    return out


# -- checks ---------------------------------------------------------------------------
def _decimate(vertices: NDArray[Any], faces: NDArray[Any], target: int) -> tuple[NDArray[Any], NDArray[Any]]:
    from brainpainter.atlas.meshing import import_pymeshlab

    ml = import_pymeshlab()
    ms = ml.MeshSet()
    ms.add_mesh(ml.Mesh(vertex_matrix=vertices, face_matrix=faces.astype(np.int32)))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=int(target), preservetopology=True,
                                                preservenormal=True)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def check_region(r: RegionMesh, centre: NDArray[Any], radius: float, max_faces: int = MAX_FACES) -> None:
    """Drop far-away pieces, decimate a huge mesh, wind a closed mesh outwards (notes in `r.notes`)."""
    import trimesh

    mesh = trimesh.Trimesh(r.vertices, r.faces, process=False)
    comp = trimesh.graph.connected_component_labels(  # type: ignore[no-untyped-call]
        mesh.face_adjacency, node_count=len(mesh.faces))
    n_comp = int(comp.max()) + 1 if len(comp) else 0
    tri_centre = r.vertices[r.faces].mean(axis=1)
    far = np.zeros(len(r.faces), dtype=bool)
    for c in range(n_comp):
        sel = comp == c
        if np.linalg.norm(tri_centre[sel].mean(axis=0) - centre) > STRAY_RADII * radius:
            far |= sel
    if far.all():
        raise BrainPainterError(
            f"{r.file} lies far outside the other meshes (its centre at "
            f"{np.round(tri_centre.mean(0), 1).tolist()}, the brain's at {np.round(centre, 1).tolist()}); "
            "give meshes in one coordinate system")
    if far.any():
        n_pieces = len(np.unique(comp[far]))
        r.notes.append(f"dropped {n_pieces} piece(s), {int(far.sum())} faces, lying far outside the brain")
        mesh.update_faces(~far)
        mesh.remove_unreferenced_vertices()
    v, f = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    if len(f) > max_faces:
        try:
            v2, f2 = _decimate(v, f, max_faces)
            r.notes.append(f"decimated from {len(f)} to {len(f2)} faces")
            v, f = v2, f2
        except BrainPainterError as exc:
            r.notes.append(f"kept all {len(f)} faces (not decimated: {exc})")
    closed = trimesh.Trimesh(v, f, process=False)
    if closed.is_watertight and closed.volume < 0:
        f = f[:, ::-1]
        r.notes.append("turned inside out: faces rewound outwards")
    r.vertices, r.faces = v, f


def load_regions(surface_dirs: list[Path], structure_dirs: list[Path],
                 names: Mapping[str, tuple[str, tuple[str, ...]]] | None = None, *,
                 units: str | None = None, orientation: str | None = None, max_faces: int = MAX_FACES,
                 progress: Callable[[str], None] | None = None) -> tuple[list[RegionMesh], list[str]]:
    """Read, weld, transform and check every mesh of the folders.

    Parameters
    ----------
    surface_dirs : list of Path
        Folders whose hemisphere-named meshes are the outer surface.
    structure_dirs : list of Path
        Folders of structures (subcortical views).
    names : mapping, optional
        From :func:`read_names`.
    units : {"mm", "um", "cm", "m"} or None
    orientation : str or None
        Three letters, see :func:`orientation_matrix`.
    max_faces : int
    progress : callable, optional
        Called with each file name.

    Returns
    -------
    regions : list of RegionMesh
    report : list of str
        What was found and assumed (units, orientation, left/right check).
    """
    if units is not None and units not in UNITS:
        raise choice_error("--units", units, UNITS)
    to_ras = orientation_matrix(orientation) if orientation else np.eye(3)
    scale = UNITS[units] if units else 1.0
    names = dict(names or {})
    regions: list[RegionMesh] = []
    keys: dict[str, Path] = {}
    for folders, surface in ((surface_dirs, True), (structure_dirs, False)):
        for folder in folders:
            for f, hemi, name, aliases in name_regions(mesh_files(folder), names):
                if progress is not None:
                    progress(f.name)
                v, faces = read_mesh(f)
                if not len(faces) or not len(v):
                    raise BrainPainterError(f"{f} has no faces; every region file needs a triangle mesh")
                if not np.isfinite(v).all():
                    raise BrainPainterError(f"{f} has {int((~np.isfinite(v)).any(1).sum())} vertices with "
                                            "non-finite coordinates (NaN/inf); fix or remove the file")
                if faces.min() < 0 or faces.max() >= len(v):
                    raise BrainPainterError(f"{f} has faces that point at vertices it does not have; the "
                                            "file is broken")
                n_read = len(v)
                v, faces = weld(v @ to_ras.T * scale, faces)
                if np.linalg.det(to_ras) < 0:
                    faces = faces[:, ::-1]
                r = RegionMesh(f, name, hemi, "surface" if surface and hemi != "bilateral" else "structure",
                               v, faces, tuple(a for a in aliases if a != HEMI_PREFIX[hemi] + name),
                               n_read_vertices=n_read)
                if n_read > len(v):
                    r.notes.append(f"welded {n_read} -> {len(v)} vertices")
                if r.key in keys:
                    raise BrainPainterError(f"{keys[r.key].name} and {f.name} both name region {r.key!r}; "
                                            "rename one or give --names FILE")
                keys[r.key] = f
                regions.append(r)
    every = np.concatenate([r.vertices for r in regions])
    centre = np.median(every, axis=0)
    radius = float(np.percentile(np.linalg.norm(every - centre, axis=1), 90))
    for r in regions:
        check_region(r, centre, radius, max_faces)
    return regions, describe_frame(regions, units, orientation)


def describe_frame(regions: list[RegionMesh], units: str | None, orientation: str | None) -> list[str]:
    """Lines saying which units and axes were used or assumed, with the left/right check."""
    pts = np.concatenate([r.vertices for r in regions])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = " x ".join(f"{s:.4g}" for s in hi - lo)
    out = [f"units: {units} (scaled to mm); extent {size} mm" if units else
           f"units: not given, coordinates kept as they are (extent {size}; if that is not millimetres give "
           "--units um|cm|m)"]
    out.append(f"orientation: {orientation.upper()} turned into RAS" if orientation else
               "orientation: not given, axes taken as RAS (x right, y anterior, z superior); if the brain "
               "comes out turned, give --orientation (e.g. LPS, or PIL for BrainGlobe's asr)")
    side = {h: np.mean([r.vertices[:, 0].mean() for r in regions if r.hemi == h])
            for h in ("lh", "rh") if any(r.hemi == h for r in regions)}
    if len(side) == 2:
        ok = side["lh"] < side["rh"]
        out.append(f"left/right: left regions at mean x {side['lh']:.3g}, right at {side['rh']:.3g}: " +
                   ("left is on the left (x right)" if ok else
                    "LEFT REGIONS LIE ON THE RIGHT: the x axis points left; give --orientation (e.g. LAS)"))
    return out


# -- writing --------------------------------------------------------------------------
def image_aspect(regions: list[RegionMesh]) -> float | None:
    """Width / height of the images of a brain with this extent when the user gives no size.

    Seen from above (anterior up), a brain fills ``0.926 * 0.75 * LR / AP`` of a 4:3 image's
    width; one longer than wide (a mouse, 0.81; a rat) gets an image as much narrower as brings
    that to about 75 %, between 3:4 and 4:3 (a mouse: square). None: 4:3 is right (a brain about
    as wide as long; the human templates keep their 1200 x 900).
    """
    pts = np.concatenate([r.vertices for r in regions])
    lr, ap = np.ptp(pts[:, 0]), np.ptp(pts[:, 1])
    if ap <= 0 or lr / ap >= 0.9:
        return None
    return float(round(min(max(0.926 * (lr / ap) / 0.75, 0.75), 4 / 3), 2))


def _concat(meshes: list[RegionMesh]) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    verts, faces, labels, base = [], [], [], 0
    for i, r in enumerate(meshes):
        verts.append(r.vertices)
        faces.append(r.faces + base)
        labels.append(np.full(len(r.faces), i, np.int16))
        base += len(r.vertices)
    return (np.concatenate(verts).astype(np.float32), np.concatenate(faces).astype(np.int32),
            np.concatenate(labels))


def write_mesh_template(folder: Path, name: str, regions: list[RegionMesh], *, source: dict[str, Any],
                        surface_also: tuple[str, ...] = (),
                        glass: tuple[NDArray[Any], NDArray[Any]] | None = None) -> dict[str, Any]:
    """Write ``folder/template/``: cortex per hemisphere, structures, glass (each hemisphere's surface).

    Structures whose keys are in `surface_also` are drawn in the surface
    views too (a mouse's cerebellum, seen from above), in the same colour.
    `glass` (vertices, faces), a whole-brain mesh (BrainGlobe's root), is the
    glass brain of a brain without surface regions (stored once, as ``rh``).
    """
    tdir = folder / "template"
    tdir.mkdir()
    cortex: dict[str, Any] = {}
    glass_entries: dict[str, Any] = {}
    if glass is not None:
        save_npz(tdir / "glass.npz", {"vertices": np.asarray(glass[0], np.float32),
                                      "faces": np.asarray(glass[1], np.int32)})
        glass_entries["rh"] = {"file": "glass.npz"}
    for hemi in ("lh", "rh"):
        part = [r for r in regions if r.hemi == hemi and (r.part == "surface" or r.key in surface_also)]
        if not part:
            continue
        v, f, lab = _concat(part)
        save_npz(tdir / f"cortex-{hemi}.npz", {"faces": f, "face_label": lab, "pial": v,
                                               "source_vertex": np.arange(len(v), dtype=np.int32)})
        cortex[hemi] = {"file": f"cortex-{hemi}.npz", "names": [r.name for r in part]}
        glass_entries[hemi] = {"file": f"cortex-{hemi}.npz", "vertices": "pial"}  # the surface, as glass
    structures = [r for r in regions if r.part == "structure"]
    manifest: dict[str, Any] = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "name": name,
        "source": {"subject": name, "builder": "brainpainter.atlas.meshfolder", **source},
        "space": "the meshes' coordinates turned into RAS (x right, y anterior, z superior)",
        "axes": {"anterior": "+y", "superior": "+z"},
        "surfaces": ["pial"],
        "labels": {name: {"source": "region meshes", "regions": [], "cortex": cortex}},
        "glass": glass_entries,
    }
    if structures:
        v, f, lab = _concat(structures)
        save_npz(tdir / "subcortical.npz", {"vertices": v, "faces": f, "face_label": lab})
        manifest["subcortical"] = {"file": "subcortical.npz", "structures": [
            {"name": r.key, "index": i} for i, r in enumerate(structures)]}
    pts = np.concatenate([r.vertices for r in regions])
    manifest["bounds"] = {"pial": [pts.min(axis=0).round(4).tolist(), pts.max(axis=0).round(4).tolist()]}
    (tdir / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
    return manifest


def build_mesh_atlas(name: str, meshes: list[Path], *, subcortical: list[Path] | None = None,
                     names: str | Path | None = None, units: str | None = None,
                     orientation: str | None = None,
                     title: str = "", description: str = "", citation: str = "", out: Path,
                     max_faces: int = MAX_FACES, colors: Mapping[str, tuple[int, int, int]] | None = None,
                     surface_also: tuple[str, ...] = (),
                     progress: Callable[[str], None] | None = None,
                     views: tuple[str, ...] = ()) -> dict[str, Any]:
    """Read the mesh folders and write an atlas folder into `out` (existing, empty).

    Parameters
    ----------
    name : str
    meshes : list of Path
        Folders of region meshes (hemisphere-named ones form the outer surface).
    subcortical : list of Path, optional
        Folders of structures drawn in the subcortical views.
    names : path, optional
        ``--names`` CSV (:func:`read_names`).
    units, orientation : str or None
        See :func:`load_regions`.
    title, description, citation : str
    out : Path
    max_faces : int
    colors : mapping of region key to RGB 0-255, optional
        Region colours (default: matplotlib's ``tab20`` cycle).
    surface_also : tuple of str
        Keys of hemisphere structures drawn in the surface views too.
    progress : callable, optional
    views : tuple of str
        The atlas's default views (:attr:`Atlas.views`), when not the usual ones.

    Returns
    -------
    dict
        The ``atlas.json`` written (with ``report``: the lines of :func:`describe_frame`).
    """
    regions, report = load_regions(list(meshes), list(subcortical or []),
                                   read_names(names) if names else None, units=units, orientation=orientation,
                                   max_faces=max_faces, progress=progress)
    source = {"folders": [p.name for p in [*meshes, *(subcortical or [])]], "units": units or "as given",
              "orientation": (orientation or "as given (taken as RAS)").upper()}
    return write_mesh_atlas(name, regions, report, source=source, title=title, description=description
                            or f"{len(regions)} region meshes from {', '.join(source['folders'])}.",
                            citation=citation, out=out, colors=colors, surface_also=surface_also, views=views)


def write_mesh_atlas(name: str, regions: list[RegionMesh], report: list[str], *, source: dict[str, Any],
                     title: str, description: str, citation: str, out: Path,
                     colors: Mapping[str, tuple[int, int, int]] | None = None,
                     surface_also: tuple[str, ...] = (),
                     groups: Mapping[str, tuple[str, tuple[str, ...]]] | None = None,
                     glass: tuple[NDArray[Any], NDArray[Any]] | None = None,
                     views: tuple[str, ...] = ()) -> dict[str, Any]:
    """Write ``atlas.json``, ``regions.tsv`` and ``template/`` of checked region meshes into `out`.

    `groups` maps a region that is not drawn (a BrainGlobe parent structure)
    to its full name and the drawn regions it colours (its descendants);
    `glass` is a whole-brain glass mesh; see :func:`write_mesh_template`;
    `views` are the atlas's default views (:attr:`Atlas.views`), when not the usual ones.
    Returns the ``atlas.json`` written.
    """
    import matplotlib

    cycle = matplotlib.colormaps["tab20"].colors  # type: ignore[attr-defined]
    rows = []
    for i, r in enumerate(regions):
        default = cast(tuple[int, int, int], tuple(round(255 * c) for c in cycle[i % len(cycle)][:3]))
        rows.append(Region(i + 1, r.name, r.hemi, "cortical" if r.part == "surface" else "subcortical",
                           (colors or {}).get(r.key, default), r.aliases))
    known = {r.key for r in regions if r.part == "structure" and r.hemi != "bilateral"}
    for key in surface_also:
        if key not in known:
            raise choice_error("--also-surface", key, known, "Name a structure with a hemisphere.")
    for key, (full, _) in (groups or {}).items():
        rows.append(Region(len(rows) + 1, key, "bilateral", "subcortical",
                           (colors or {}).get(key, (200, 200, 200)), (full,) if full and full != key else ()))
    write_regions_tsv(rows, out / "regions.tsv")
    write_mesh_template(out, name, regions, source=source, surface_also=tuple(surface_also), glass=glass)
    meta = {
        "name": name, "title": title or name, "kind": "meshes", "template_labels": name, "template": name,
        "description": description, "citation": citation, "aliases": [], "source": source, "report": report,
        "image_aspect": image_aspect(regions),
        **({"views": list(views)} if views else {}),
        "groups": {k: list(m) for k, (_, m) in (groups or {}).items()},
        "regions": [{"key": r.key, "file": r.file.name, "part": r.part, "n_vertices": len(r.vertices),
                     "n_faces": len(r.faces), "n_read_vertices": r.n_read_vertices, "notes": r.notes}
                    for r in regions],
    }
    (out / "atlas.json").write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return meta


def add_mesh_atlas(name: str, meshes: list[Path], *, replace: bool = False, out: str | Path | None = None,
                   **kwargs: Any) -> tuple[Path, dict[str, Any]]:
    """``brainpainter atlas add NAME --meshes DIR``: build and store (or write to `out`).

    Returns the atlas folder and its ``atlas.json``.
    """
    return store_built(name, lambda stage: build_mesh_atlas(name, meshes, out=stage, **kwargs),
                       replace=replace, out=out)

