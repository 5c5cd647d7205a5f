"""Inspect a template: its manifest plus checks (the validation step of a build).

:func:`template_problems` lists everything wrong with a template directory
(regions without faces, cracks, missing arrays, sizes over budget); the
builder runs it on the staged directory before moving it into place, and
:func:`template_report` (``brainpainter template info``) shows it with sizes
and load time.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshing import BUILDER_HINT, count_self_intersections, import_pymeshlab
from brainpainter.atlas.template import SURFACES, Template, load_template
from brainpainter.errors import BrainPainterError

#: Largest allowed |mesh volume / voxel volume - 1| of a subcortical structure.
VOLUME_TOLERANCE = 0.05


def _crossings(vertices: NDArray[Any], faces: NDArray[Any]) -> int | None:
    """Self-intersecting faces of a mesh, or None where pymeshlab (the ``builder`` extra) is missing.

    Reading a template needs no extra: without pymeshlab this one check is
    reported as not run, never as an error.
    """
    try:
        import_pymeshlab()
    except BrainPainterError:
        return None
    return count_self_intersections(vertices, faces)


def _open_edges(faces: NDArray[Any]) -> int:
    from brainpainter_builder.cortex import open_edge_count

    return open_edge_count(faces)


def _load_all(path: Path) -> tuple[Template, float]:
    """Load a template and every array it references; return it and the seconds taken."""
    t0 = time.perf_counter()
    tpl = load_template(path)
    for labels in tpl.label_sets:
        for hemi in ("lh", "rh"):
            tpl.cortex(labels, hemi)
    tpl.subcortical()
    for hemi in ("lh", "rh"):
        tpl.glass(hemi)
    return tpl, time.perf_counter() - t0


def _cortex_checks(tpl: Template) -> tuple[dict[str, Any], list[str]]:
    out: dict[str, Any] = {}
    problems: list[str] = []
    for labels in tpl.label_sets:
        entry = tpl.manifest["labels"][labels]
        regions = entry.get("regions")
        out[labels] = {}
        for hemi in ("lh", "rh"):
            mesh = tpl.cortex(labels, hemi)
            names = mesh.label_names
            wanted = list(regions) if regions is not None else [
                n for n in names if n not in _non_regions()]
            counts = np.bincount(mesh.face_label.astype(np.int64), minlength=len(names))
            by_name = {n: int(counts[i]) for i, n in enumerate(names)}
            empty = [n for n in wanted if by_name.get(n, 0) == 0]
            n_v = len(mesh.source_vertex)
            bad_shape = [s for s in SURFACES if s in mesh.vertices and mesh.vertices[s].shape != (n_v, 3)]
            missing_surf = [s for s in tpl.surfaces if s not in mesh.vertices]
            opened = _open_edges(mesh.faces)
            crossing = entry["cortex"][hemi].get("self_intersecting_faces", {})
            out[labels][hemi] = {
                "n_vertices": n_v,
                "n_faces": len(tpl.base_cortex(labels, hemi).faces) if "base" not in entry["cortex"][hemi]
                else len(mesh.faces),
                "n_faces_drawn": len(mesh.faces),
                "n_regions": len(wanted) - len(empty),
                "regions_without_faces": empty,
                "open_edges": {s: opened for s in tpl.surfaces if s in mesh.vertices},
                "self_intersecting_faces": crossing,
            }
            where = f"cortex {labels}/{hemi}"
            if empty:
                problems.append(f"{where}: regions without faces {empty}")
            if opened:
                problems.append(f"{where}: {opened} open boundary edges (expected 0)")
            folded = {s: c["template"] for s, c in crossing.items() if c.get("template")}
            if folded:
                problems.append(f"{where}: self-intersecting faces {folded} (expected 0)")
            if missing_surf or bad_shape:
                problems.append(f"{where}: surfaces missing {missing_surf} or misshapen {bad_shape}")
            if len(mesh.faces) and (mesh.faces.min() < 0 or mesh.faces.max() >= n_v):
                problems.append(f"{where}: faces index vertices out of range")
            if len(mesh.face_label) != len(mesh.faces) or mesh.face_label.max(initial=0) >= len(names):
                problems.append(f"{where}: face_label does not match faces / names")
    return out, problems


def _non_regions() -> frozenset[str]:
    from brainpainter_builder.sources import NON_REGIONS

    return NON_REGIONS


def _subcortical_checks(tpl: Template) -> tuple[dict[str, Any], list[str]]:
    problems: list[str] = []
    sub = tpl.subcortical()
    counts = np.bincount(sub.face_label.astype(np.int64), minlength=len(sub.label_names))
    empty = [n for n, c in zip(sub.label_names, counts, strict=False) if c == 0]
    if empty:
        problems.append(f"subcortical: structures without faces {empty}")
    off = []
    for s in tpl.manifest["subcortical"]["structures"]:
        ref = s.get("voxel_volume_mm3")
        if ref and abs(s["volume_mm3"] / ref - 1.0) > VOLUME_TOLERANCE:
            off.append(f"{s['name']} ({s['volume_mm3'] / ref - 1.0:+.1%})")
    folded = {s["name"]: s["self_intersecting_faces"]["template"] for s in tpl.manifest["subcortical"][
        "structures"] if s.get("self_intersecting_faces", {}).get("template")}
    if folded:
        problems.append(f"subcortical: self-intersecting faces {folded} (expected 0)")
    if off:
        problems.append(f"subcortical: mesh volume off the voxel volume by more than "
                        f"{VOLUME_TOLERANCE:.0%}: {off}")
    return {
        "n_structures": len(sub.label_names),
        "n_faces": len(sub.faces),
        "structures_without_faces": empty,
        "open_edges": _open_edges(sub.faces),
        "self_intersecting_faces": {
            k: sum(s.get("self_intersecting_faces", {}).get(k, 0)
                   for s in tpl.manifest["subcortical"]["structures"])
            for k in ("decimated", "template")},
    }, problems


def template_problems(path: str | Path, max_size_mb: float | None = None) -> list[str]:
    """Everything wrong with the template at `path`; an empty list when it is valid."""
    return _check(Path(path), max_size_mb)[1]


def _check(path: Path, max_size_mb: float | None) -> tuple[dict[str, Any], list[str]]:
    tpl, load_s = _load_all(path)
    problems: list[str] = []
    cortex, p = _cortex_checks(tpl)
    problems += p
    subcortical, p = _subcortical_checks(tpl)
    problems += p
    glass = {}
    for hemi in ("lh", "rh"):
        v, f = tpl.glass(hemi)
        glass[hemi] = {"n_vertices": len(v), "n_faces": len(f), "open_edges": _open_edges(f),
                       "self_intersecting_faces": _crossings(v, f)}
        if glass[hemi]["open_edges"]:
            problems.append(f"glass/{hemi}: {glass[hemi]['open_edges']} open edges")
        if glass[hemi]["self_intersecting_faces"]:
            problems.append(f"glass/{hemi}: {glass[hemi]['self_intersecting_faces']} self-intersecting faces")
    files = {p.name: p.stat().st_size for p in tpl.files()}
    size = sum(files.values())
    if max_size_mb is not None and size > max_size_mb * 1e6:
        problems.append(f"template is {size / 1e6:.1f} MB, over the {max_size_mb:g} MB budget; "
                        "lower target_faces (--target-faces) or build fewer atlases")
    info = {
        "path": str(path),
        "manifest": tpl.manifest,
        "checks": {"cortex": cortex, "subcortical": subcortical, "glass": glass},
        "files": files,
        "size_bytes": size,
        "size_mb": round(size / 1e6, 2),
        "load_s": round(load_s, 3),
        "problems": problems,
        "notes": tpl.notes,
        "ok": not problems,
    }
    return info, problems


def template_report(path: str | Path) -> dict[str, Any]:
    """Manifest plus checks of a template directory.

    Returns
    -------
    dict
        ``manifest``; ``checks`` (per label set and hemisphere: faces
        stored and drawn (after splitting boundary faces), vertices,
        regions without faces, open boundary edges per surface;
        subcortical structures without faces; glass hulls); ``files`` (bytes
        per file), ``size_bytes`` / ``size_mb`` (total on disk), ``load_s``
        (seconds to load the template and read all its arrays), ``problems``
        (list of str) and ``ok``.
    """
    return _check(Path(path), None)[0]


def format_report(report: dict[str, Any]) -> str:
    """Human-readable summary of :func:`template_report`'s result (several lines)."""
    m = report["manifest"]
    src = m.get("source", {})
    lines = [
        f"template {m.get('name')!r} at {report['path']}",
        f"  source: {src.get('subject', '?')} ({src.get('freesurfer', 'unknown')}), "
        f"space: {m.get('space', '?')}",
        f"  surfaces: {', '.join(m.get('surfaces', []))}; size {report['size_mb']} MB in "
        f"{len(report['files'])} files; load + read all arrays {report['load_s']} s",
    ]
    for labels, per_hemi in report["checks"]["cortex"].items():
        entry = m["labels"][labels]
        parts = []
        for hemi, c in per_hemi.items():
            opened = sorted(set(c["open_edges"].values()))
            drawn = c.get("n_faces_drawn", c["n_faces"])
            parts.append(f"{hemi} {c['n_regions']} regions, {c['n_faces']} faces"
                         f"{f' ({drawn} drawn, boundary faces split)' if drawn != c['n_faces'] else ''}, "
                         f"open edges {'/'.join(map(str, opened))}")
            if c["regions_without_faces"]:
                parts[-1] += f", without faces: {c['regions_without_faces']}"
        lines.append(f"  {labels} ({entry.get('source', '?')}): " + "; ".join(parts))
        folds = [f"{hemi} {s} {c['decimated']}->{c['template']}" for hemi, h in per_hemi.items()
                 for s, c in h.get("self_intersecting_faces", {}).items()]
        if folds:
            lines.append("    self-intersecting faces (decimated -> template): " + ", ".join(folds))
    sub = report["checks"]["subcortical"]
    structures = m["subcortical"]["structures"]
    worst = max(structures, key=lambda s: abs(s.get("volume_error", 0.0)), default=None)
    line = f"  subcortical: {sub['n_structures']} structures, {sub['n_faces']} faces"
    if worst is not None and "volume_error" in worst:
        line += f", worst volume error {worst['volume_error']:+.2%} ({worst['name']})"
    crossing = sub.get("self_intersecting_faces", {})
    if crossing:
        line += (f", self-intersecting faces {crossing.get('decimated', 0)} (first decimation) -> "
                 f"{crossing.get('template', 0)}")
    lines.append(line)
    glass = report["checks"]["glass"]
    if any(g["self_intersecting_faces"] is None for g in glass.values()):
        lines.append("  glass: " + ", ".join(f"{h} {g['n_faces']} faces" for h, g in glass.items())
                     + f"; self-intersections not checked (needs pymeshlab: {BUILDER_HINT})")
    else:
        lines.append("  glass: " + ", ".join(f"{h} {g['n_faces']} faces, {g['self_intersecting_faces']} "
                                             "self-intersecting" for h, g in glass.items()))
    lines += [f"  note: {n}" for n in report.get("notes", [])]
    if report["problems"]:
        lines.append("  PROBLEMS:")
        lines += [f"    - {p}" for p in report["problems"]]
    else:
        lines.append("  checks: ok")
    return "\n".join(lines)
