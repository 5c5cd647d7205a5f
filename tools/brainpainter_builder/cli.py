"""``brainpainter template build`` and ``template info``: the builder's commands.

The core command line never imports the builder: it finds this group through
the ``brainpainter.commands`` entry point (see ``pyproject.toml``) and imports
it only when a ``template`` command runs.
"""

from __future__ import annotations

import json
from pathlib import Path

import click

from brainpainter.cli.params import OutPath, split_commas
from brainpainter.errors import BrainPainterError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


@click.group(context_settings=CONTEXT)
def template() -> None:
    """Build and inspect templates (the meshes a renderer draws)."""


@template.command("build", context_settings=CONTEXT)
@click.argument("subject_dir", type=click.Path(path_type=Path, file_okay=False))
@click.option("--out", "-o", required=True, type=OutPath(path_type=Path, file_okay=False))
@click.option("--atlas", "atlases", multiple=True, callback=split_commas,
              help="Label sets to build: dk, destrieux, dkt (default: all three).")
@click.option("--surface", "surfaces", multiple=True, callback=split_commas,
              help="Surfaces: pial, white, inflated (default: all three).")
@click.option("--target-faces", type=int, default=None,
              help="Faces per hemisphere and label set after decimation (default: builder's choice).")
@click.option("--name", default=None, help="Template name (default: the subject folder's name).")
@click.option("--gcs-dir", type=click.Path(path_type=Path, file_okay=False), default=None,
              help="Folder with FreeSurfer's ?h.DKTaparc...gcs(.gz) classifier atlases, to derive DKT.")
def template_build(subject_dir: Path, out: Path, atlases: list[str], surfaces: list[str],
                   target_faces: int | None, name: str | None, gcs_dir: Path | None) -> None:
    """Build a template from a FreeSurfer SUBJECT_DIR (surf/, label/, mri/aseg.mgz)."""
    import importlib.util

    missing = [pip for mod, pip in (("pymeshlab", "pymeshlab"), ("skimage", "scikit-image"))
               if importlib.util.find_spec(mod) is None]
    if missing:
        raise BrainPainterError(f"template build needs {' and '.join(missing)}, which are not installed; "
                                "install them with: pip install 'brainpainter[builder]'")
    from brainpainter_builder.build import build_template

    kwargs: dict[str, object] = {"name": name, "gcs_dir": gcs_dir, "target_faces": target_faces}
    if atlases:
        kwargs["atlases"] = tuple(atlases)
    if surfaces:
        kwargs["surfaces"] = tuple(surfaces)
    path = build_template(subject_dir, out, **{k: v for k, v in kwargs.items() if v is not None})
    click.echo(f"template written to {path}")


@template.command("info", context_settings=CONTEXT)
@click.argument("name_or_path", default="fsaverage")
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def template_info(name_or_path: str, as_json: bool) -> None:
    """Manifest and checks of a template (default: the bundled fsaverage)."""
    from brainpainter.atlas.template import load_template
    from brainpainter_builder.report import format_report, template_report

    report = template_report(load_template(name_or_path).path)
    if as_json:
        click.echo(json.dumps(report, indent=2))
    else:
        click.echo(format_report(report))
