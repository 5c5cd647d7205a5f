"""Layers (issue 35): each kind of data's own colour options, checked when given, refused when unused."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.color.scale import ScaleOptions
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.layers import LayerOptions
from brainpainter.rendering.run import prepare_run


def test_a_later_layer_shares_the_first_scale_unless_given_its_own():
    base = ScaleOptions(cmap="viridis", vmin=1.5, vmax=4)
    options = LayerOptions(tracts_cmap="magma", tracts_vmin=0.3)
    assert options.scale_options("regions", base, first=True) == base
    assert LayerOptions().scale_options("tracts", base, first=False) is None  # shares the first's
    own = options.scale_options("tracts", base, first=False)
    assert own is not None and (own.cmap, own.vmin, own.vmax) == ("magma", 0.3, None)  # not the plain vmax
    first = LayerOptions(regions_gradient="blue,red").scale_options("regions", base, first=True)
    assert first is not None and (first.cmap, first.gradient, first.vmin) == (None, "blue,red", 1.5)


@pytest.mark.parametrize(("given", "message"), [
    ({"map_alpha": 1.5}, "--map-alpha must be a number from 0"),
    ({"tracts_cmap": "magmaa"}, "--tracts-\\* options: colour map 'magmaa' is not a matplotlib"),
    ({"map_vmin": 2.0, "map_vmax": 1.0}, "vmax must be greater than vmin"),
])
def test_bad_layer_options_are_one_line_errors(given, message):
    with pytest.raises(BrainPainterError, match=message):
        LayerOptions(**given)


def test_options_of_a_layer_not_drawn_are_refused(tmp_path):
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,lh_insula\ns1,1\n")
    with pytest.raises(BrainPainterError, match="--tracts-cmap colours tract values, but this run draws none "
                                                "\\(it draws regions\\); give tract values"):
        prepare_run(table, tracts_cmap="magma")
    with pytest.raises(BrainPainterError, match="--map-alpha colours the map, but this run draws none"):
        prepare_run(table, map_alpha=0.5)
    with pytest.raises(BrainPainterError, match="--regions-label colours region values, but this run draws "
                                                "none \\(it draws map\\)"):
        prepare_run(None, lh=np.zeros(10242), regions_label="thickness")
    run = prepare_run(table, regions_cmap="viridis", regions_label="thickness")  # drawn: accepted
    assert [(la.kind, la.label, la.scale.name) for la in run.layers] == [("regions", "thickness", "viridis")]


def test_a_contour_that_cannot_be_read_names_contour(tmp_path):
    message = (r"^--contour .*lh\.none\.mgh.* does not exist.*; --contour takes one file whose name says "
               r"its hemisphere, or two: LH,RH\.$")
    with pytest.raises(BrainPainterError, match=message):
        prepare_run(None, lh=np.zeros(10242), contour=str(tmp_path / "lh.none.mgh"))


def test_each_automatic_scale_of_its_own_is_named_by_its_layer(capsys):
    from types import SimpleNamespace

    from brainpainter.cli.params import echo_scale
    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.layers import Layer

    regions = make_scale(cmap="viridis", vmin=1.5, vmax=4)
    chosen = SimpleNamespace(chosen="values >= 0", describe=lambda: "viridis 0-4.7 (values >= 0)")
    echo_scale(regions, (Layer("regions", regions), Layer("map", chosen)))  # type: ignore[arg-type]
    assert capsys.readouterr().out == "map scale: viridis 0-4.7 (values >= 0)\n"
    echo_scale(chosen)
    assert capsys.readouterr().out == "scale: viridis 0-4.7 (values >= 0)\n"
