"""BrainGlobe atlases: ``brainpainter atlas add NAME --brainglobe ATLAS_NAME`` from the user's local copy.

Reads an atlas that is already in BrainGlobe's folder (``~/.brainglobe`` or
``--brainglobe-dir``) through the ``brainglobe-atlasapi`` package (the
``brainglobe`` extra); nothing is downloaded. The chosen structures
(``--structures`` acronyms, or every structure at ``--depth N`` of the
structure tree plus shallower leaves; default: the leaves) become regions
named by their acronyms, with the full names as aliases, drawn as structures
(:mod:`brainpainter.atlas.meshfolder`) inside the root mesh as glass brain.
Every other structure with drawn descendants becomes a region group: a table
value for ``Isocortex`` colours its drawn descendants unless they have a value
of their own (:meth:`brainpainter.atlas.model.Atlas.expand`).

Meshes are in micrometres, with axes named by the atlas's BrainGlobe
orientation (``asr``: the origin's corner; the axes increase towards posterior,
inferior and left, ``PIL``); they are turned into RAS millimetres.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshfiles import orientation_matrix, weld
from brainpainter.atlas.meshfolder import RegionMesh, check_region, describe_frame
from brainpainter.atlas.user import store_built
from brainpainter.errors import BrainPainterError, choice_error

EXTRA_HINT = 'pip install "brainpainter[brainglobe]" (or: pip install brainglobe-atlasapi)'
_OPPOSITE = {"a": "P", "p": "A", "s": "I", "i": "S", "r": "L", "l": "R"}


def increasing_axes(origin: str) -> str:
    """BrainGlobe's orientation (origin corner, ``"asr"``) as where the axes increase (``"PIL"``)."""
    code = str(origin).strip().lower()
    if len(code) != 3 or any(c not in _OPPOSITE for c in code):
        raise BrainPainterError(f"BrainGlobe orientation {origin!r} is not three of a/p, s/i, r/l")
    return "".join(_OPPOSITE[c] for c in code)


def _default_dir() -> Path:
    try:
        from brainglobe_atlasapi.config import read_config

        return Path(read_config()["default_dirs"]["brainglobe_dir"]).expanduser()
    except Exception:  # an unreadable config: BrainGlobe's own default
        return Path.home() / ".brainglobe"


def open_local_atlas(atlas_name: str, brainglobe_dir: str | Path | None = None) -> Any:
    """The ``BrainGlobeAtlas`` of a locally present atlas (never downloads).

    Raises
    ------
    BrainPainterError
        brainglobe-atlasapi is not installed, or the atlas is not in the folder.
    """
    try:
        from brainglobe_atlasapi import BrainGlobeAtlas
    except ImportError:
        raise BrainPainterError(f"reading BrainGlobe atlases needs the brainglobe-atlasapi package: "
                                f"{EXTRA_HINT}") from None
    folder = Path(brainglobe_dir).expanduser() if brainglobe_dir else _default_dir()
    v3 = folder / "brainglobe-atlasapi" / "atlases" / atlas_name
    v2 = [*folder.glob(f"{atlas_name}_v*"), *(folder / "brainglobe-atlasapi").glob(f"{atlas_name}_v*")]
    if not (v3.is_dir() or v2):
        raise BrainPainterError(
            f"BrainGlobe atlas {atlas_name!r} is not in {folder}; brainpainter does not download. On a "
            f"machine with internet run: brainglobe install -a {atlas_name}  (then copy {folder} here, or "
            "give --brainglobe-dir)")
    try:
        return BrainGlobeAtlas(atlas_name, brainglobe_dir=folder, check_latest=False)
    except Exception as exc:  # a broken local copy
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise BrainPainterError(f"cannot read BrainGlobe atlas {atlas_name!r} in {folder}: "
                                f"{reason}") from None


def select_structures(structures: dict[int, dict[str, Any]], acronyms: list[str] | None,
                      depth: int | None) -> list[dict[str, Any]]:
    """The structures drawn: the given acronyms, those at `depth` (and shallower leaves), or the leaves."""
    by_acronym = {s["acronym"]: s for s in structures.values()}
    if acronyms:
        unknown = [a for a in acronyms if a not in by_acronym]
        if unknown:
            raise choice_error("--structures", unknown[0], by_acronym)
        return [by_acronym[a] for a in dict.fromkeys(acronyms)]
    parents = {p for s in structures.values() for p in s["structure_id_path"][:-1]}
    if depth is not None:
        if depth < 1:
            raise BrainPainterError(f"--depth must be 1 or more (0 is the root, the whole brain); "
                                    f"{depth} was given")
        return [s for s in structures.values()
                if len(s["structure_id_path"]) - 1 == depth
                or (len(s["structure_id_path"]) - 1 < depth and s["id"] not in parents)]
    return [s for s in structures.values() if s["id"] not in parents and len(s["structure_id_path"]) > 1]


def _mesh_arrays(mesh: Any) -> tuple[NDArray[Any], NDArray[Any]]:
    """Vertices and triangles of a meshio mesh (or anything with ``vertices``/``faces``)."""
    if hasattr(mesh, "cells_dict"):
        tri = mesh.cells_dict.get("triangle")
        if tri is None:
            raise ValueError("no triangles")
        return np.asarray(mesh.points, np.float64), np.asarray(tri, np.int64)
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)


def _fetch_hint(atlas_name: str) -> str:
    """How to get meshes (brainglobe-atlasapi 3 installs an atlas without them, fetches each on first use)."""
    return (f"on a machine with internet, BrainGlobeAtlas({atlas_name!r}).mesh_from_structure(ACRONYM) "
            "fetches each one (brainglobe-atlasapi); then copy the BrainGlobe folder here")


def _local_mesh(bg: Any, acronym: str, to_ras: NDArray[Any],
                not_here: list[str]) -> tuple[NDArray[Any], NDArray[Any]] | None:
    """The structure's mesh in RAS millimetres (welded, outward), or None; never downloads it.

    A format-3 mesh file that is not on disk is added to `not_here` (``mesh_from_structure`` would fetch
    it from BrainGlobe's server).
    """
    file = bg.structures[acronym].get("mesh_filename")
    if file is not None and not Path(file).is_file():
        not_here.append(acronym)
        return None
    try:
        v, f = _mesh_arrays(bg.mesh_from_structure(acronym))
    except Exception:  # no mesh for this structure
        return None
    v, f = weld(v @ to_ras.T, f)
    return v, (f[:, ::-1] if np.linalg.det(to_ras) < 0 else f)


def build_brainglobe_atlas(name: str, atlas_name: str, *, out: Path, brainglobe_dir: str | Path | None = None,
                           structures: list[str] | None = None, depth: int | None = None, title: str = "",
                           description: str = "", citation: str = "",
                           progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Write an atlas folder into `out` (existing, empty) from a local BrainGlobe atlas.

    Returns the ``atlas.json`` written.
    """
    from brainpainter.atlas.meshfolder import write_mesh_atlas

    bg = open_local_atlas(atlas_name, brainglobe_dir)
    tree: dict[int, dict[str, Any]] = {int(k): v for k, v in bg.structures.items()
                                       if isinstance(k, int | np.integer)}
    chosen = select_structures(tree, structures, depth)
    origin = str(bg.metadata.get("orientation", "asr"))
    letters = increasing_axes(origin)
    to_ras = orientation_matrix(letters) * 1e-3  # micrometres -> mm

    def load(acronym: str) -> tuple[NDArray[Any], NDArray[Any]] | None:
        return _local_mesh(bg, acronym, to_ras, not_here)

    regions: list[RegionMesh] = []
    skipped: list[str] = []
    not_here: list[str] = []
    for s in chosen:
        if progress is not None:
            progress(s["acronym"])
        got = load(s["acronym"])
        if got is None or not len(got[1]):
            if s["acronym"] not in not_here:
                skipped.append(s["acronym"])
            continue
        regions.append(RegionMesh(Path(f"{s['id']}.obj"), s["acronym"], "bilateral", "structure", got[0],
                                  got[1], (s["name"],) if s["name"] != s["acronym"] else ()))
    if not regions:
        if not_here:
            raise BrainPainterError(
                f"none of the chosen structures of {atlas_name!r} has its mesh on this machine "
                f"({len(not_here)} not fetched: {', '.join(not_here[:5])}); brainpainter does not download; "
                + _fetch_hint(atlas_name))
        raise BrainPainterError(f"none of the chosen structures of {atlas_name!r} has a mesh; choose others "
                                "with --structures or --depth")
    every = np.concatenate([r.vertices for r in regions])
    centre = np.median(every, axis=0)
    radius = float(np.percentile(np.linalg.norm(every - centre, axis=1), 90))
    for r in regions:
        check_region(r, centre, radius)
    drawn = {int(r.file.stem): r.name for r in regions}
    groups: dict[str, tuple[str, tuple[str, ...]]] = {}
    for s in tree.values():
        if s["id"] in drawn:
            continue
        members = tuple(drawn[d["id"]] for d in tree.values()
                        if d["id"] in drawn and s["id"] in d["structure_id_path"][:-1])
        if members:
            groups[s["acronym"]] = (s["name"], members)
    root = next((s for s in tree.values() if len(s["structure_id_path"]) == 1), None)
    glass = load(root["acronym"]) if root is not None and root["id"] not in drawn else None
    colors = {s["acronym"]: tuple(int(c) for c in s.get("rgb_triplet", (200, 200, 200))[:3])
              for s in tree.values()}
    report = describe_frame(regions, "um", letters)
    report[1] = f"orientation: BrainGlobe {origin!r} (axes increase towards {letters}) turned into RAS"
    if skipped:
        report.append(f"no mesh for {len(skipped)} structure(s): {', '.join(skipped[:10])}")
    if not_here:
        report.append(f"mesh not on this machine for {len(not_here)} structure(s), not drawn: "
                      f"{', '.join(not_here[:10])}; " + _fetch_hint(atlas_name))
    source = {"brainglobe_atlas": atlas_name, "units": "um", "orientation": f"{origin} (BrainGlobe)",
              "selection": {"structures": structures, "depth": depth}}
    return write_mesh_atlas(
        name, regions, report, source=source, title=title or f"{atlas_name} (BrainGlobe)",
        description=description or f"{len(regions)} structures of the BrainGlobe atlas {atlas_name}.",
        citation=citation or str(bg.metadata.get("citation", "")), out=out,
        colors=colors, groups=groups, glass=glass)  # type: ignore[arg-type]


def add_brainglobe_atlas(name: str, atlas_name: str, *, replace: bool = False, out: str | Path | None = None,
                         **kwargs: Any) -> tuple[Path, dict[str, Any]]:
    """``brainpainter atlas add NAME --brainglobe ATLAS_NAME``: build and store (or write to `out`)."""
    return store_built(name, lambda stage: build_brainglobe_atlas(name, atlas_name, out=stage, **kwargs),
                       replace=replace, out=out)
