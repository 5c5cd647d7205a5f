"""A colour bar per scaled layer (issue 35) in movies and in the HTML export, as in figures."""

from __future__ import annotations

import base64
import re

import numpy as np
import pytest
from test_tracts import bundle, write

from brainpainter.color.scale import make_scale

MAGMA_END, VIRIDIS_END = (252, 253, 191), (253, 231, 37)


def _has(pixels, rgb, tol=6) -> bool:
    return bool((np.abs(pixels[..., :3].astype(int) - np.asarray(rgb)).max(axis=-1) <= tol).sum() >= 20)


@pytest.fixture
def layers(tmp_path):
    """Thickness on regions, FA on two bundles: the table, and the options that give FA its own scale."""
    folder = tmp_path / "bundles"
    folder.mkdir()
    write(folder / "AF_L.trk", bundle(-25.0))
    write(folder / "CST_R.tck", bundle(25.0, seed=1))
    table = tmp_path / "thick.csv"
    table.write_text("Image-name-unique,Left-insula,Left-precuneus,AF_L,CST_R\nA,1.5,4,0.3,0.7\nB,2,3,0.4,0.6\n")
    return table, {"tracts": [str(folder)], "tracts_space": "template", "cmap": "viridis", "vmin": 1.5,
                   "vmax": 4, "tracts_cmap": "magma", "tracts_vmin": 0.3, "tracts_vmax": 0.7,
                   "tracts_label": "FA", "max_streamlines": 20}


def test_movie_frames_draw_one_bar_per_layer_one_under_the_other():
    from brainpainter.media.frames import FrameComposer

    thick, fa = make_scale(cmap="viridis", vmin=1.5, vmax=4), make_scale(cmap="magma", vmin=0.3, vmax=0.7)
    one = FrameComposer(1, (320, 240), thick, [0.0, 1.0], label="thickness")
    two = FrameComposer(1, (320, 240), thick, [0.0, 1.0], label="thickness", more_bars=[(fa, "FA")])
    assert _has(one.canvas, VIRIDIS_END) and not _has(one.canvas, MAGMA_END)
    assert _has(two.canvas, VIRIDIS_END) and _has(two.canvas, MAGMA_END)
    assert two.size[1] > one.size[1] and two.size[0] == one.size[0]


def test_a_movie_of_regions_and_tracts_shows_both_bars(tmp_path, layers, tiny):
    from PIL import Image

    from brainpainter.media.movie import make_movie
    from brainpainter.testing import stand_in

    table, options = layers
    with stand_in() as renderer:
        result = make_movie(table, "dk", out=tmp_path / "m.gif", views="lateral-left", frames_per_step=2,
                            template=str(tiny), renderer=renderer, width=160, height=120, progress=False,
                            **options)
    with Image.open(result.path) as gif:
        frame = np.asarray(gif.convert("RGB"))
    footer = frame[120:]  # under the render: caption, timeline and the bars
    assert _has(footer, VIRIDIS_END, 12) and _has(footer, MAGMA_END, 12)


def test_the_html_export_shows_a_bar_per_layer(tmp_path, layers, tiny):
    from io import BytesIO

    from PIL import Image

    from brainpainter.media.export import export

    table, options = layers
    page = export(table, tmp_path / "p.html", row="A", template=str(tiny), **options).read_text()
    bars = [np.asarray(Image.open(BytesIO(base64.b64decode(png))).convert("RGB"))
            for png in re.findall(r'<img (?:id|class)="colorbar" alt="colour bar" src="data:image/png;base64,'
                                  r'([A-Za-z0-9+/=]+)"', page)]
    assert len(bars) == 2
    assert _has(bars[0], VIRIDIS_END) and not _has(bars[0], MAGMA_END)
    assert _has(bars[1], MAGMA_END) and not _has(bars[1], VIRIDIS_END)


def test_an_export_of_a_map_has_its_tracts_too(tmp_path, layers):
    """A map with tracts exports the tracts' tubes in their own scale's colours (the export dropped them)."""
    from matplotlib import colormaps

    from brainpainter.media.export import _row_meshes
    from brainpainter.rendering.run import prepare_run

    _, options = layers
    fa = tmp_path / "fa.csv"
    fa.write_text("Image-name-unique,AF_L,CST_R\nA,0.3,0.7\n")
    options = {**options, "tract_values": str(fa), "tracts_space": "template", "cmap": None}
    run = prepare_run({"lh": np.zeros(10242), "rh": np.zeros(10242)}, **options)
    _, meshes = _row_meshes(run, 0)
    tubes = [m for m in meshes if m.part == "tracts"]
    assert {m.part for m in meshes} >= {"lh", "rh", "tracts"} and len(tubes) == 2
    colours = {tuple(np.round(np.asarray(m.color)[..., :3].reshape(-1, 3)[0], 2)) for m in tubes}
    assert colours == {tuple(np.round(colormaps["magma"](x)[:3], 2)) for x in (0.0, 1.0)}


def test_a_map_with_tracts_is_opaque_and_shows_the_tracts_in_a_subcortical_view(tmp_path, layers):
    """``--cortex auto`` with a map: the map keeps its colours (opaque cortex), the default views add
    ``subcortical`` where the tracts show (before: the map as glass at 0.12 opacity, no view inside)."""
    from brainpainter.rendering.run import prepare_run

    _, options = layers
    options = {"tracts": options["tracts"], "tracts_space": "template"}  # direction colours
    run = prepare_run({"lh": np.zeros(10242), "rh": np.zeros(10242)}, **options)
    assert run.settings.cortex == "opaque" and "subcortical" in [v.name for v in run.views]
    run = prepare_run({"lh": np.zeros(10242), "rh": np.zeros(10242)}, **options, cortex="glass")
    assert run.settings.cortex == "glass"


def test_tract_values_with_a_map_get_a_scale_of_their_own(tmp_path, layers):
    """FA with a thickness map: the bundles on FA's own range, under a bar of their own (they shared
    the map's scale, spanning the map alone: every bundle the colour of the map bar's first end)."""
    from brainpainter.rendering.layers import colorbar_layers
    from brainpainter.rendering.run import prepare_run

    _, options = layers
    fa = tmp_path / "fa.csv"
    fa.write_text("bundle,fa\nAF_L,0.35\nCST_R,0.6\n")
    thickness = {"lh": np.linspace(2, 3, 10242), "rh": np.linspace(2, 3, 10242)}
    run = prepare_run(thickness, tracts=options["tracts"], tracts_space="template", tract_values=str(fa))
    by_kind = {layer.kind: layer for layer in run.layers}
    assert [layer.kind for layer in colorbar_layers(run.layers)] == ["map", "tracts"]
    tracts = by_kind["tracts"].scale
    assert (tracts.vmin, tracts.vmax) == pytest.approx((0.35, 0.6))
    assert not np.allclose(tracts(np.array([0.35]))[0], tracts(np.array([0.6]))[0])


def test_a_tracts_label_alone_gives_the_tracts_a_bar_of_their_own(tmp_path, layers):
    """``--tracts-label FA`` without other tract options: a bar named FA (the label was dropped, the
    bundles drawn on the regions' scale under the regions' bar)."""
    from brainpainter.rendering.layers import colorbar_layers
    from brainpainter.rendering.run import prepare_run

    table, options = layers
    run = prepare_run(table, tracts=options["tracts"], tracts_space="template", tracts_label="FA")
    assert [(la.kind, la.label) for la in colorbar_layers(run.layers)] == [("regions", "thick.csv"),
                                                                            ("tracts", "FA")]
    tracts = run.layers[1].scale
    assert (tracts.vmin, tracts.vmax) == pytest.approx((0.3, 0.7))
    shared = prepare_run(table, tracts=options["tracts"], tracts_space="template")
    assert [la.kind for la in colorbar_layers(shared.layers)] == ["regions"]


@pytest.mark.parametrize(("views", "labels"), [("lateral-left", ["thickness"]),
                                               ("lateral-left,subcortical", ["thickness", "FA"])])
def test_a_figure_draws_the_tracts_bar_only_where_a_view_shows_them(tmp_path, layers, tiny, views, labels):
    """A map with FA in cortex views only (the cortex opaque): one bar, the map's, named by its
    ``map_label`` (an FA bar named what no view showed, and the map's own label was dropped)."""
    from brainpainter.media.figure import make_figure
    from brainpainter.testing import stand_in

    _, options = layers
    fa = tmp_path / "fa.csv"
    fa.write_text("bundle,fa\nAF_L,0.3\nCST_R,0.7\n")
    with stand_in() as renderer:
        result = make_figure({"lh": np.linspace(2, 3, 10242), "rh": np.linspace(2, 3, 10242)},
                             tracts=options["tracts"], tracts_space="template", tract_values=str(fa),
                             template=str(tiny), renderer=renderer, views=views, width=160, height=120,
                             map_label="thickness", tracts_label="FA", progress=False)
    assert [ax.get_xlabel() for ax in result.colorbar_axes] == labels


def test_the_first_bar_is_named_by_label_else_its_layer_s_own_label():
    from brainpainter.rendering.layers import Layer, first_bar_label

    scale = make_scale(cmap="viridis", vmin=0, vmax=1)
    one = (Layer("map", scale, label="lh.thick"),)
    two = (*one, Layer("tracts", scale, label="FA"))
    assert first_bar_label(one, None, None) is None  # one bar, nothing given: no file name under it
    assert first_bar_label(one, None, "thickness (mm)") == "thickness (mm)"  # --map-label, Scene label=
    assert first_bar_label(one, "z", "thickness (mm)") == "z"  # --label first
    assert first_bar_label(two, None, None) == "lh.thick"  # beside another bar: each names its layer


def test_one_hemisphere_s_map_is_drawn_in_its_own_views(tmp_path):
    """``--lh`` alone: lateral- and medial-left (before: the right views too, plain underlay)."""
    from brainpainter.rendering.run import prepare_run

    run = prepare_run({"lh": np.arange(10242.0)})
    assert [v.name for v in run.views] == ["lateral-left", "medial-left"]
    run = prepare_run({"rh": np.arange(10242.0)}, views="lateral-left")
    assert [v.name for v in run.views] == ["lateral-left"]
