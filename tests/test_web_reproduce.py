"""The page's "make it again": the ``brainpainter render`` command and the Python call of an upload and its
options (brainpainter.web.reproduce), checked by parsing them with the CLI's own click command and Python's
parser: what they give is what the web run is given."""

from __future__ import annotations

import ast
import shlex
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("fastapi")

from brainpainter.web.options import RenderOptions
from brainpainter.web.reproduce import OUT, reproduce

TABLE = b"Image-name-unique,Left-Hippocampus\nsub1,0.5\n"


def parsed(command: str) -> tuple[list[str], dict[str, Any]]:
    """The INPUTs and the API keywords that ``brainpainter render`` makes of `command`, those that differ
    from the command's defaults."""
    from brainpainter.cli.options import render_kwargs
    from brainpainter.cli.render import render

    def kwargs(args: list[str]) -> tuple[list[str], dict[str, Any]]:
        params = dict(render.make_context("render", args).params)
        assert params.pop("out") == Path(OUT)
        return [str(p) for p in params.pop("inputs")], render_kwargs(params)

    words = shlex.split(command)
    assert words[:2] == ["brainpainter", "render"], command
    inputs, given = kwargs(words[2:])
    default = kwargs(["-o", OUT])[1]
    return inputs, {k: v for k, v in given.items() if k not in default or v != default[k]}


def called(snippet: str) -> tuple[list[Any], dict[str, Any]]:
    """The positional and keyword arguments of the ``brainpainter.render`` call in `snippet`."""
    call = next(n for n in ast.walk(ast.parse(snippet)) if isinstance(n, ast.Call))
    assert ast.unparse(call.func) == "brainpainter.render"
    return ([ast.literal_eval(a) for a in call.args],
            {k.arg: ast.literal_eval(k.value) for k in call.keywords if k.arg})


def test_a_table_with_changed_options_is_the_same_run_on_the_command_line_and_in_python():
    o = RenderOptions(views="lateral-left,subcortical", gradient="white,blue", vmin=0, vmax=1.5,
                      size="320x240", hide=["cerebellum, Left-Hippocampus"], nan_color="#8C8C8C",
                      background="#ffffff", outline_color="#ff0000", quality="high", strict=True,
                      underlay="curv", max_streamlines=100, glass_opacity=0.12)
    got = reproduce(TABLE, "my table.csv", o)
    inputs, cli = parsed(got["command"])
    assert inputs == ["my table.csv"]
    want = {k: v for k, v in o.run_kwargs().items() if k in cli}
    assert cli == want | {"hide": ["cerebellum", "Left-Hippocampus"]}, (got["command"], cli)
    # only what differs from the defaults (white is #ffffff; map and tract options not for a table)
    assert set(cli) == {"views", "gradient", "vmin", "vmax", "width", "height", "hide", "outline_color",
                        "quality", "strict"}
    assert "--underlay" not in got["command"] and "--max-streamlines" not in got["command"]
    args, kwargs = called(got["python"])
    assert args == ["my table.csv"] and kwargs.pop("out") == OUT
    assert kwargs == cli


def test_tracts_from_a_zip_of_subject_folders_and_a_transparent_map(tmp_path):
    import nibabel as nib
    from test_tracts import bundle, write

    from brainpainter.web.maps import build_bundle
    from brainpainter.web.tracts import build_tract_bundle

    (tmp_path / "sub_1").mkdir()
    write(tmp_path / "sub_1" / "AF_L.trk", bundle(-30.0, n=5))

    with zipfile.ZipFile(tmp_path / "bundles.zip", "w") as zf:
        for s in ("sub_1", "sub_2"):
            zf.write(tmp_path / "sub_1" / "AF_L.trk", f"{s}/AF_L.trk")
    (tmp_path / "fa.csv").write_text("AF_left\n0.5\n")
    work = tmp_path / "work"
    work.mkdir()
    build_tract_bundle(work, [tmp_path / "bundles.zip", tmp_path / "fa.csv"], 10, 1000, subject="sub_2")
    tracts = (work / "bundle.bin").read_bytes()
    o = RenderOptions(tracts="0" * 32, tract_radius=0.5, tracts_affine="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
    inputs, cli = parsed(reproduce(TABLE, "t.csv", o, tracts)["command"])
    assert inputs == ["t.csv"]
    assert cli["tracts"] == ["bundles/sub_2"] and cli["tract_values"] == "fa.csv"
    assert cli["tract_radius"] == 0.5 and cli["tracts_affine"] == "affine.txt"
    # the tracts alone: their values table is the input
    inputs, cli = parsed(reproduce(tracts, "bundles.zip + fa.csv", RenderOptions())["command"])
    assert inputs == ["fa.csv"] and cli["tracts"] == ["bundles/sub_2"] and "tract_values" not in cli

    for hemi in ("lh", "rh"):
        nib.freesurfer.write_morph_data(str(tmp_path / f"{hemi}.thickness"), np.ones(10242, np.float32))
    mwork = tmp_path / "map"
    mwork.mkdir()
    build_bundle(mwork, [("lh", tmp_path / "lh.thickness"), ("rh", tmp_path / "rh.thickness")], 10)
    o = RenderOptions(transparent=True, underlay="curv", threshold=0.5)
    got = reproduce((mwork / "bundle.bin").read_bytes(), "lh.thickness + rh.thickness", o)
    inputs, cli = parsed(got["command"])
    assert inputs == [] and cli["lh"] == "lh.thickness" and cli["rh"] == "rh.thickness"
    assert cli["background"] is None and cli["underlay"] == "curv" and cli["threshold"] == 0.5
    args, kwargs = called(got["python"])
    assert args == [] and kwargs["lh"] == "lh.thickness" and kwargs["background"] is None


def test_figure_movie_and_export_commands_parse_with_their_cli_commands():
    """A job's command is its own CLI command's (figure, movie, export), with only the options it takes."""
    from brainpainter.cli.export import export
    from brainpainter.cli.media import figure, movie

    o = RenderOptions(views="lateral-left", size="320x240", cmap="viridis", quality="high")
    for kind, params, command in (("figure", {"format": "png", "dpi": 150, "grid": True}, figure),
                                  ("movie", {"format": "gif", "hold": 3, "easing": "smooth"}, movie),
                                  ("export", {"row": 1, "image": "stage 2", "title": "Stage 2"}, export)):
        got = reproduce(TABLE, "t.csv", o, kind=kind, params=params)
        words = shlex.split(got["command"])
        assert words[:3] == ["brainpainter", kind, "t.csv"], got["command"]
        given = command.make_context(kind, words[2:]).params
        if kind == "export":
            assert given["out"] == Path("stage_2.html") and given["row"] == "stage 2"
            assert given["fmt"] == "html" and given["title"] == "Stage 2" and given["cmap"] == "viridis"
            assert "--size" not in got["command"] and "--views" not in got["command"]
        else:
            assert given["out"] == Path(f"{kind}.{params['format']}") and given["size"] == (320, 240)
            assert all(given[k] == v for k, v in params.items() if k != "format"), (params, given)
        args, kwargs = called(got["python"].replace(f"brainpainter.{kind}(", "brainpainter.render("))
        assert args == ["t.csv"] and kwargs["cmap"] == "viridis"


def test_a_map_over_a_table_is_the_same_layers_on_the_command_line_and_in_python(tmp_path):
    """Option map (a map upload drawn over the table) is --lh/--rh beside INPUT, with each layer's options."""
    import nibabel as nib

    from brainpainter.web.maps import build_bundle

    for hemi in ("lh", "rh"):
        nib.freesurfer.write_morph_data(str(tmp_path / f"{hemi}.thickness"), np.ones(10242, np.float32))
    work = tmp_path / "map"
    work.mkdir()
    build_bundle(work, [("lh", tmp_path / "lh.thickness"), ("rh", tmp_path / "rh.thickness")], 10)
    o = RenderOptions(map="0" * 32, map_cmap="magma", map_vmin=1.5, map_alpha=0.5, map_label="thickness (mm)",
                      regions_label="tau", threshold=0.5)
    got = reproduce(TABLE, "t.csv", o, map_upload=(work / "bundle.bin").read_bytes())
    inputs, cli = parsed(got["command"])
    assert inputs == ["t.csv"]
    assert cli == {"lh": "lh.thickness", "rh": "rh.thickness", "map_cmap": "magma", "map_vmin": 1.5,
                   "map_alpha": 0.5, "map_label": "thickness (mm)", "regions_label": "tau", "threshold": 0.5}
    args, kwargs = called(got["python"])
    assert args == ["t.csv"] and kwargs.pop("out") == OUT and kwargs == cli


def test_the_preview_has_its_own_command_its_row_from_its_view():
    """Issue 44 item 18: the page shows the command of the preview it draws (its row, its view), as the
    command line parses it and as the Python call takes it."""
    from brainpainter.cli.render import render

    o = RenderOptions(views="lateral-left,subcortical", gradient="white,blue", size="320x240")
    got = reproduce(TABLE, "t.csv", o, preview=("sub1", "dorsal"))
    assert got["command"] == ("brainpainter render t.csv -o brainpainter-out --gradient white,blue --size "
                              "320x240 --rows sub1 --views dorsal")
    params = render.make_context("render", shlex.split(got["command"])[2:]).params
    assert (params["rows"], params["views"], params["gradient"]) == ("sub1", "dorsal", "white,blue")
    args, kwargs = called(got["python"])
    assert args == ["t.csv"] and (kwargs["rows"], kwargs["views"]) == ("sub1", "dorsal")
    assert "--rows" not in reproduce(TABLE, "t.csv", o, preview=(None, "dorsal"))["command"]


def test_line_options_are_options_of_the_api_the_run_and_its_command():
    """Issue 44's line options (--outline-style, --contour-*) on the web, as on the command line."""
    from brainpainter.web.options import prepare

    o = RenderOptions(outline="dk", outline_style="dashed", outline_width=2, contour_width=3,
                      contour_color="#ff0000", contour_style="dashed")
    settings = prepare(TABLE, "t.csv", o).run.settings
    assert (settings.outline_style, settings.contour_width, settings.contour_style) == (
        "dashed", 3.0, "dashed")
    assert settings.contour_color == (1.0, 0.0, 0.0)
    got = reproduce(TABLE, "t.csv", o)
    _, cli = parsed(got["command"])
    lines = ("outline_style", "contour_width", "contour_color", "contour_style")
    assert {k: cli[k] for k in lines} == {"outline_style": "dashed", "contour_width": 3.0,
                                          "contour_color": "#ff0000", "contour_style": "dashed"}
    assert called(got["python"])[1]["contour_style"] == "dashed"
    with pytest.raises(ValueError, match="dotted"):
        RenderOptions(outline_style="dotted")


def test_a_volume_drawn_as_blobs_and_cut_is_the_same_run_on_the_command_line_and_in_python(tmp_path):
    """Option volume_surface draws a volume upload as blobs: --volume-surface FILE, with --clip planes."""
    from test_web_maps import mni_volume

    from brainpainter.rendering.run import prepare_run
    from brainpainter.web.maps import build_bundle
    from brainpainter.web.options import prepare

    volume = tmp_path / "zstat1.nii.gz"
    volume.write_bytes(mni_volume())
    work = tmp_path / "vol"
    work.mkdir()
    (work / volume.name).write_bytes(volume.read_bytes())   # the upload's copy (the bundle takes it)
    build_bundle(work, [(None, work / volume.name)], 10)
    bundle = (work / "bundle.bin").read_bytes()
    o = RenderOptions(volume_surface=True, threshold=2.3, min_cluster_mm3=10, clip=["x<0", "z>20"],
                      views="dorsal,cutaway-left")
    got = reproduce(bundle, "zstat1.nii.gz", o)
    inputs, cli = parsed(got["command"])
    assert inputs == [] and "--volume " not in got["command"], got["command"]
    assert cli == {"volume_surface": "zstat1.nii.gz", "threshold": 2.3, "min_cluster_mm3": 10.0,
                   "clip": ["x<0", "z>20"], "views": "dorsal,cutaway-left"}, cli
    args, kwargs = called(got["python"])
    assert args == [] and kwargs.pop("out") == OUT and kwargs == cli
    web = prepare(bundle, "zstat1.nii.gz", o).run           # the web's run is the command's
    cli_run = prepare_run(None, **{**cli, "volume_surface": str(volume)})
    assert web.blobs.digest() == cli_run.blobs.digest() and web.table.images == cli_run.table.images
    assert [v.name for v in web.views] == [v.name for v in cli_run.views]
    assert web.options.scene.clip == cli_run.options.scene.clip == ("x<0", "z>20")
    assert web.layers[0].label == cli_run.layers[0].label == "zstat1.nii.gz"
