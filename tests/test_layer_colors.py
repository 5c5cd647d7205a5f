"""Each layer's colours of one image and of a movie's frame between two (brainpainter/layers/, issue 43):
the first layer's (regions, a map) with those of the layers over it added, read off the layers by the
one ``Run``, never by their kind."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from brainpainter.color.scale import ColourScale, cmap_colors
from brainpainter.layers.over import KeyFrameColors, over_layers
from brainpainter.layers.regions import RegionValues, region_colors
from brainpainter.layers.tracts import tract_colors
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.run import prepare_run
from brainpainter.tracts.values import MISSING_TRACT_KEY, TractValues

SCALE = ColourScale(cmap_colors("viridis"), 0.0, 4.0)
TRACTS = ColourScale(cmap_colors("magma"), 0.0, 1.0)


def _rgb(scale: ColourScale, value: float) -> tuple[float, float, float]:
    c = scale(np.array([value]))[0]
    return float(c[0]), float(c[1]), float(c[2])


@dataclass(frozen=True)
class Dots:
    """A drawn layer whose one key's colour is its row's value on the scale."""

    kind: str = "dots"

    def colors(self, row: int) -> dict[str, tuple[float, float, float]]:
        return {"dots:0": _rgb(SCALE, float(row))}


def test_a_region_table_s_colours_and_a_frame_between_two_rows():
    table = pd.DataFrame({"Image-name-unique": ["a", "b"], "Left-insula": [0.0, 4.0],
                          "Left-precuneus": [4.0, 0.0]})
    run = prepare_run(table, "dk", vmin=0, vmax=4, cmap="viridis")
    regions = run.base
    assert isinstance(regions, RegionValues) and run.coloring == "regions"
    one = run.colors(1)
    assert one == region_colors(run.table.row(1), run.table.atlas, run.scale)
    half = run.blend(0, 1, 0.5)  # both regions halfway: the scale's middle
    assert np.allclose(half["Left-insula"], _rgb(run.scale, 2.0))
    assert np.allclose(half["Left-precuneus"], _rgb(run.scale, 2.0))
    assert run.blend(0, 1, 0.0) == run.colors(0) and run.blend(0, 1, 1.0) == run.colors(1)


def test_the_layers_over_the_first_add_their_keys_and_blend_on_their_own_scales():
    values = TractValues(("a", "b"), ("tract:AF_left", "tract:CST_right"),
                         np.array([[0.0, 1.0], [1.0, np.nan]]), (("AF_left", 1), ("CST_right", 1)))
    layers = (Layer("regions", SCALE), Layer("tracts", TRACTS))
    over = over_layers(layers, ["a", "b"], values, drawn=(Dots(),))
    tracts, dots = over
    assert tracts.colors(0) == tract_colors({"tract:AF_left": 0.0, "tract:CST_right": 1.0}, TRACTS)
    half = tracts.blend(0, 1, 0.5)
    assert np.allclose(half["tract:AF_left"], _rgb(TRACTS, 0.5))  # on the tracts' scale, not the regions'
    assert half["tract:CST_right"] == TRACTS.nan_color  # NaN in a key frame: NaN between them
    assert MISSING_TRACT_KEY in half  # bundles drawn without a value take the missing colour
    assert isinstance(dots, KeyFrameColors)
    assert dots.blend(1, 3, 0.7) == Dots().colors(1)  # a drawn layer's frame: the first key frame's
    only_regions = over_layers((Layer("regions", SCALE),), ["a", "b"], values)
    assert np.allclose(only_regions[0].colors(1)["tract:AF_left"], _rgb(SCALE, 1.0))  # no scale: the first's


def test_a_map_run_s_frame_between_two_images_and_the_layers_over_it(tmp_path):
    lh = np.zeros((2, 10242), np.float32)
    lh[1] = 2.0
    run = prepare_run({"lh": lh, "rh": lh}, "dk", vmin=0, vmax=4, cmap="viridis")
    assert run.coloring == "vertices"
    a, b = run.colors(0), run.colors(1)
    half = run.blend(0, 1, 0.5)
    assert np.allclose(half.vertices["lh"], run.blend(1, 0, 0.5).vertices["lh"])
    assert not np.allclose(half.vertices["lh"], a.vertices["lh"]) and not np.allclose(
        half.vertices["lh"], b.vertices["lh"])
    assert np.array_equal(run.blend(0, 0, 0.3).vertices["lh"], a.vertices["lh"])  # one image: itself


def test_a_map_given_as_arrays_has_its_bar_labelled_map_not_by_its_type():
    lh = np.linspace(0, 3, 10242).astype(np.float32)
    assert [layer.label for layer in prepare_run({"lh": lh, "rh": lh}, "dk").layers] == ["map"]  # was
    # "lh=ndarray, rh=ndarray"
    assert prepare_run({"lh": lh, "rh": lh}, "dk", map_label="thickness").layers[0].label == "thickness"
