"""``atlas add NAME --meshes DIR`` and ``--brainglobe ATLAS_NAME``: option checks and the report."""

from __future__ import annotations

import time
from pathlib import Path

import click

from brainpainter.errors import BrainPainterError


def add_from_meshes_or_brainglobe(
        name: str, *, meshes: tuple[Path, ...], sub_meshes: tuple[Path, ...], also_surface: tuple[str, ...],
        names: Path | None, lut_and_names: bool, units: str | None, orientation: str | None,
        brainglobe: str | None, brainglobe_dir: Path | None, structures: str | None, depth: int | None,
        title: str, description: str, citation: str, replace: bool, out: Path | None) -> None:
    """Check the options of a mesh-folder or BrainGlobe atlas, build it, and print what was found and done."""
    mesh_input = bool(meshes or sub_meshes)
    if not mesh_input and (names is not None or units is not None or orientation is not None or also_surface):
        raise BrainPainterError("--names, --units, --orientation and --also-surface go with --meshes DIR (a "
                                "folder of region meshes)")
    if brainglobe is None and (brainglobe_dir is not None or structures is not None or depth is not None):
        raise BrainPainterError("--brainglobe-dir, --structures and --depth go with --brainglobe ATLAS_NAME")
    t0 = time.perf_counter()
    where = "written to" if out is not None else "added in"
    if brainglobe is not None:
        from brainpainter.atlas.brainglobe import add_brainglobe_atlas

        if structures is not None and depth is not None:
            raise BrainPainterError("give --structures or --depth, not both")
        folder, meta = add_brainglobe_atlas(
            name, brainglobe, brainglobe_dir=brainglobe_dir, depth=depth, title=title,
            description=description, citation=citation, replace=replace, out=out,
            structures=[a.strip() for a in structures.split(",") if a.strip()] if structures else None)
        for line in meta["report"]:
            click.echo(line)
        click.echo(f"atlas {name!r} {where} {folder} ({len(meta['regions'])} structures drawn, "
                   f"{len(meta['groups'])} parent structures; {time.perf_counter() - t0:.1f} s)")
        return
    from brainpainter.atlas.meshfolder import add_mesh_atlas

    if lut_and_names:
        raise BrainPainterError("give the region names once: --names FILE (or --lut FILE), not both")
    folder, meta = add_mesh_atlas(name, list(meshes), subcortical=list(sub_meshes), names=names, units=units,
                                  orientation=orientation, surface_also=also_surface, title=title,
                                  description=description, citation=citation, replace=replace, out=out)
    for line in meta["report"]:
        click.echo(line)
    for r in meta["regions"]:
        if r["notes"] and not all(n.startswith("welded") for n in r["notes"]):
            click.echo(f"note: {r['file']}: {'; '.join(r['notes'])}")
    n_weld = sum(1 for r in meta["regions"] if r["n_read_vertices"] > r["n_vertices"])
    n_surface = sum(1 for r in meta["regions"] if r["part"] == "surface")
    click.echo(f"atlas {name!r} {where} {folder} ({n_surface} surface regions, "
               f"{len(meta['regions']) - n_surface} structures; {n_weld} meshes welded; "
               f"{time.perf_counter() - t0:.1f} s)")
    if out is None:
        click.echo(f"render with: brainpainter render TABLE --atlas {name} --views dorsal,lateral-left,"
                   "subcortical --out DIR")
