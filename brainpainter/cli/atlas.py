"""``brainpainter atlas list|show|add|remove``: the installed atlases, and your own."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from brainpainter.atlas.model import SPACES
from brainpainter.cli.options import option_group, parse_size
from brainpainter.cli.params import CONTEXT, OutPath, echo_json
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.options import SceneOptions
from brainpainter.rendering.settings import RenderSettings


# -- atlas --------------------------------------------------------------------
@click.group(context_settings=CONTEXT)
def atlas() -> None:
    """List, inspect, add and remove atlases."""


@atlas.command("list", context_settings=CONTEXT)
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def atlas_list(as_json: bool) -> None:
    """Atlases: built-in, from plugins, and yours (atlas add)."""
    from brainpainter.atlas import registry
    rows = []
    for name in registry.atlases.names():
        entry = next((e for e in registry.atlases.entries() if e.name == name), None)
        row: dict[str, Any] = {"name": name, "aliases": list(entry.aliases) if entry else [],
               "distribution": entry.distribution if entry else "(session)"}
        try:
            a = registry.atlases.get(name)
            row.update(title=a.title, n_cortical_per_hemisphere=len(a.cortical("lh")),
                       n_subcortical=len(a.subcortical()), error=None)
        except BrainPainterError as exc:
            row.update(error=str(exc))
        rows.append(row)
    if as_json:
        echo_json(rows)
        return
    for r in rows:
        alias = f" (alias: {', '.join(r['aliases'])})" if r["aliases"] else ""
        if r["error"]:
            click.echo(f"{r['name']}{alias}  BROKEN: {r['error']}")
        else:
            click.echo(f"{r['name']}{alias}  {r['title']}: {r['n_cortical_per_hemisphere']} cortical "
                       f"regions per hemisphere, {r['n_subcortical']} subcortical  [{r['distribution']}]")


@atlas.command("show", context_settings=CONTEXT)
@click.argument("name")
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
@click.option("--image", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="Also draw a reference PNG: every region in its colour-table colour, views side by side.")
@click.option("--views", default=None,
              help="Views of the reference image [default: lateral-left,medial-left,subcortical; "
                   "subcortical,subcortical-dorsal for an atlas without cortical regions].")
@click.option("--size", default="800x600", show_default=True, help="Size of each view, WIDTHxHEIGHT.")
@option_group(SceneOptions, ("template", "surface"))
@option_group(RenderSettings, ("quality",))
@option_group(SceneOptions, ("renderer",))
def atlas_show(name: str, as_json: bool, image: Path | None, views: str | None, size: str, template: str,
               surface: str, quality: str, renderer: str) -> None:
    """Regions of atlas NAME, with hemisphere, colour and aliases; --image draws them."""
    from brainpainter.atlas.registry import get_atlas

    a = get_atlas(name)
    if image is not None:
        from brainpainter.media.atlas_image import reference_image
        from brainpainter.rendering.painter import VOLUME_VIEWS

        if views is None:
            views = "lateral-left,medial-left,subcortical" if a.cortical() else ",".join(VOLUME_VIEWS)
        reference_image(a, image, views=views, size=parse_size(size), template=template, surface=surface,
                        quality=quality, renderer=renderer)
        if not as_json:
            click.echo(f"reference image of {a.name} written to {image}")
            return
    from brainpainter.connectome.order import describe_order, node_order

    if as_json:
        echo_json({**a.to_dict(), "connectome_order": list(node_order(a)[1])})
        return
    click.echo(f"{a.name}: {a.title}")
    if a.description:
        click.echo(f"  {a.description}")
    click.echo(f"  Node order: {describe_order(a)}.")
    for hemi in ("lh", "rh"):
        regs = a.cortical(hemi)
        click.echo(f"\ncortical, {'left' if hemi == 'lh' else 'right'} hemisphere ({len(regs)}):")
        for r in regs:
            click.echo(f"  {r.key}")
    sub = a.subcortical()
    click.echo(f"\nsubcortical ({len(sub)}):")
    for r in sub:
        alias = f"  (also: {', '.join(r.aliases)})" if r.aliases else ""
        click.echo(f"  {r.key}{alias}")
    if a.citation:
        click.echo(f"\nCite: {a.citation}")


@atlas.command("add", context_settings=CONTEXT)
@click.argument("name")
@click.option("--annot", "annots", multiple=True, metavar="HEMI=FILE",
              help="Label map per hemisphere: lh=FILE and rh=FILE (FreeSurfer .annot or GIFTI .label.gii "
                   "on the template's surface).")
@click.option("--dlabel", "dlabel", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="CIFTI-2 label file (.dlabel.nii, e.g. Schaefer or Gordon on fsLR 32k): its label names "
                   "and colours become the regions (fsLR resampled onto fsaverage by nearest vertex).")
@click.option("--config", "config", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="Region-group TOML file (a base atlas and named groups of its regions).")
@click.option("--volume", "volume", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="Label volume (NIfTI/MGH of integer labels): one smooth mesh per label, drawn in the "
                   "subcortical views.")
@click.option("--lut", "lut", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="Look-up table for --volume: FreeSurfer LUT, BIDS dseg.tsv or CSV of index,name.")
@click.option("--space", default=None, type=click.Choice((*SPACES, "fsLR"), case_sensitive=False),
              help="Space of --volume (mapped into the template's; see docs/atlases.md) [default: "
                   "MNI152NLin2009cAsym]; with --dlabel, fsaverage or fsLR: the mesh of a 163842-vertex file "
                   "that does not say.")
@click.option("--own-template", is_flag=True,
              help="With --volume: the volume is a brain of its own (e.g. a mouse atlas): make a template of "
                   "its labels only (no cortex) in the volume's coordinates; --space is not used.")
@click.option("--meshes", "meshes", multiple=True, type=click.Path(path_type=Path, file_okay=False),
              help="Folder of region meshes, one region per file (OBJ, PLY, STL, OFF, GLB/glTF, GIfTI): "
                   "hemisphere-named ones (lh./Left-/_L) form the outer surface, the others are structures.")
@click.option("--subcortical-meshes", "sub_meshes", multiple=True,
              type=click.Path(path_type=Path, file_okay=False),
              help="With --meshes (or alone): folder of structures drawn in the subcortical views.")
@click.option("--also-surface", "also_surface", multiple=True, metavar="KEY",
              help="With --subcortical-meshes: a structure also drawn in the surface views (e.g. "
                   "Left-Cerebellum). Repeatable.")
@click.option("--names", "names", type=click.Path(path_type=Path, dir_okay=False), default=None,
              help="With --meshes: CSV of file,name[,aliases] naming the regions (also accepted as --lut).")
@click.option("--units", type=click.Choice(["mm", "um", "cm", "m"]), default=None,
              help="With --meshes: units of the mesh coordinates (scaled to mm); not given: kept, reported.")
@click.option("--orientation", default=None, metavar="XYZ",
              help="With --meshes: where each axis increases, e.g. RAS, LPS, PIL (BrainGlobe's 'asr'); not "
                   "given: taken as RAS and reported.")
@click.option("--brainglobe", "brainglobe", default=None, metavar="ATLAS_NAME",
              help="A BrainGlobe atlas already on this machine (e.g. allen_mouse_25um; needs "
                   "brainglobe-atlasapi; nothing is downloaded).")
@click.option("--brainglobe-dir", "brainglobe_dir", type=click.Path(path_type=Path, file_okay=False),
              default=None, help="With --brainglobe: BrainGlobe's folder (default: its configured one).")
@click.option("--structures", "structures", default=None, metavar="ACRONYMS",
              help="With --brainglobe: comma-separated acronyms of the structures drawn (default: leaves).")
@click.option("--depth", "depth", type=int, default=None,
              help="With --brainglobe: draw the structures at this depth of the tree (and shallower leaves).")
@click.option("--template", default="fsaverage", show_default=True,
              help="Template the label maps were made for.")
@click.option("--title", default="", help="Human title (default: NAME).")
@click.option("--description", default="", help="One-line description.")
@click.option("--citation", default="", help="What to cite.")
@click.option("--replace", is_flag=True, help="Replace your atlas of the same name.")
@click.option("--out", "out", type=OutPath(path_type=Path, file_okay=False), default=None,
              help="Write the atlas folder to OUT (e.g. into an atlas plugin) instead of adding it.")
def atlas_add(name: str, annots: tuple[str, ...], dlabel: Path | None, config: Path | None,
              volume: Path | None, lut: Path | None, space: str | None, own_template: bool,
              meshes: tuple[Path, ...], sub_meshes: tuple[Path, ...],
              also_surface: tuple[str, ...], names: Path | None, units: str | None, orientation: str | None,
              brainglobe: str | None, brainglobe_dir: Path | None, structures: str | None, depth: int | None,
              template: str, title: str,
              description: str, citation: str, replace: bool, out: Path | None) -> None:
    """Add atlas NAME from label maps (--annot, --dlabel), a label volume (--volume) or groups (--config).

    \b
    Examples:
      brainpainter atlas add yeo7 --annot lh=lh.Yeo2011_7Networks_N1000.annot \\
                                  --annot rh=rh.Yeo2011_7Networks_N1000.annot
      brainpainter atlas add schaefer100 --dlabel Schaefer2018_100Parcels_7Networks_order.dlabel.nii
      brainpainter atlas add lobes --config lobes.toml
      brainpainter atlas add tian_s2 --volume Tian_S2.nii.gz --lut Tian_S2.csv --space MNI152NLin6Asym
      brainpainter atlas add mymouse --meshes cortex_ply/ --subcortical-meshes deep_ply/ --units um
    """
    import time

    from brainpainter.atlas import registry
    from brainpainter.atlas import user as user_atlases
    mesh_input = bool(meshes or sub_meshes)
    if sum([bool(annots), dlabel is not None, config is not None, volume is not None, mesh_input,
            brainglobe is not None]) != 1:
        raise BrainPainterError("give either --annot lh=FILE --annot rh=FILE, --dlabel FILE.dlabel.nii, "
                                "--volume FILE --lut FILE, --meshes DIR, --brainglobe ATLAS_NAME or --config "
                                "FILE.toml (one of them)")
    if space is not None and (space not in ("fsaverage", "fsLR") if dlabel else space == "fsLR"):
        raise BrainPainterError(f"--space {space} is for {'--volume' if dlabel else '--dlabel'}; with "
                                "--dlabel give fsaverage or fsLR (or none), with --volume an MNI space")
    if brainglobe is not None or mesh_input or names or units or orientation or brainglobe_dir or structures \
            or depth is not None or also_surface:
        from brainpainter.cli.atlas_meshes import add_from_meshes_or_brainglobe

        add_from_meshes_or_brainglobe(
            name, meshes=meshes, sub_meshes=sub_meshes, also_surface=also_surface, names=names or lut,
            lut_and_names=names is not None and lut is not None, units=units, orientation=orientation,
            brainglobe=brainglobe, brainglobe_dir=brainglobe_dir, structures=structures, depth=depth,
            title=title, description=description, citation=citation, replace=replace, out=out)
        return
    if (volume is None) != (lut is None):
        raise BrainPainterError("--volume and --lut go together: the look-up table names the volume's labels")
    t0 = time.perf_counter()
    if volume is not None and lut is not None:
        from brainpainter.atlas.volumes import add_volume_atlas

        folder = add_volume_atlas(name, volume, lut, space=space or "MNI152NLin2009cAsym", template=template,
                                  title=title, description=description, citation=citation, replace=replace,
                                  out=out, own_template=own_template)
    elif config is not None:
        if out is not None:
            raise BrainPainterError("--out is for label maps (--annot); a config is a file you can ship "
                                    "as it is")
        folder = user_atlases.add_config(name, config, replace=replace)
    else:
        folder = user_atlases.add_label_map(
            name, _dlabel_maps(dlabel, template, space) if dlabel is not None else
            user_atlases.parse_annot_options(annots), template=template, title=title,
            description=description, citation=citation, replace=replace, out=out)
    if out is not None:
        from brainpainter.atlas.model import load_atlas_dir

        a = load_atlas_dir(folder)
    else:
        a = registry.atlases.get(name)
    n = {h: len(a.cortical(h)) for h in ("lh", "rh")}
    where = "written to" if out is not None else "added in"
    click.echo(f"atlas {name!r} {where} {folder} ({n['lh']} left, {n['rh']} right cortical regions, "
               f"{len(a.subcortical())} subcortical; {time.perf_counter() - t0:.1f} s)")
    if out is None:
        click.echo(f"render with: brainpainter render TABLE --atlas {name} --out DIR")


def _dlabel_maps(dlabel: Path, template: str, space: str | None) -> dict[str, Any]:
    """A dlabel's label map per hemisphere on `template`'s surface; its notes printed."""
    from brainpainter.atlas.template import load_template
    from brainpainter.maps.dlabel import dlabel_label_maps

    maps, notes = dlabel_label_maps(dlabel, load_template(template), space)
    for note in notes:
        click.echo(f"note: {note}", err=True)
    return dict(maps)


@atlas.command("remove", context_settings=CONTEXT)
@click.argument("name")
def atlas_remove(name: str) -> None:
    """Remove atlas NAME that you added with 'atlas add'."""
    from brainpainter.atlas import user as user_atlases
    target = user_atlases.link_target(name)
    folder = user_atlases.remove(name)
    click.echo(user_atlases.removal_message(name, folder, target))
