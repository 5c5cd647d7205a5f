"""Every registered renderer passes the renderer conformance suite (brainpainter.testing.check_renderer).

Runs without a GPU (the Blender renderer draws through Mesa's llvmpipe where there is none).
"""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.atlas import registry
from brainpainter.rendering.tract_parts import TractLayer
from brainpainter.testing import check_renderer


@pytest.mark.render
@pytest.mark.parametrize("name", registry.renderers.names())
def test_registered_renderer_conforms(name):
    report = check_renderer(name)
    assert report["orientation_worst_px"] < 0.04 * 160


class _Mirrored:
    """A broken renderer: the Blender renderer's image flipped left-right."""

    def __init__(self, scene):
        from brainpainter_blender import BlenderRenderer

        self._r = BlenderRenderer(scene)

    def render(self, palette, view):
        return np.ascontiguousarray(self._r.render(palette, view)[:, ::-1])

    def close(self):
        self._r.close()


@pytest.mark.render
def test_suite_catches_a_mirrored_renderer():
    pytest.importorskip("bpy")
    with pytest.raises(AssertionError, match="orientation: lateral-left"):
        check_renderer(_Mirrored, checks=("orientation",))


@pytest.mark.render
def test_tracts_check_passes_and_catches_a_mirrored_renderer():
    pytest.importorskip("bpy")
    report = check_renderer("blender", checks=("tracts",))
    assert report["tracts_worst_px"] < 0.05 * 160
    with pytest.raises(AssertionError, match="tracts: subcortical-dorsal: bundle tract:AF_left is centred"):
        check_renderer(_Mirrored, checks=("tracts",))


class _ReadsTubes:
    """A renderer that says it draws no tubes (``draws_tubes = False``) but reads them (to draw them)."""

    draws_tubes = False

    def __init__(self, scene):
        from brainpainter_blender import BlenderRenderer

        self._r = BlenderRenderer(scene)
        self.triangles = sum(len(p.triangles) for p in scene.geometry.parts if p.kind == "tract")

    def render(self, palette, view):
        return self._r.render(palette, view)

    def close(self):
        self._r.close()


@pytest.mark.render
def test_tracts_check_holds_a_renderer_to_its_draws_tubes():
    pytest.importorskip("bpy")
    with pytest.raises(AssertionError, match=r"says draws_tubes=False but built the tubes of \['tracts-lh', "
                                             r"'tracts-rh'\]"):
        check_renderer(_ReadsTubes, checks=("tracts",))
    _ReadsTubes.draws_tubes = "no"  # type: ignore[assignment]
    try:
        with pytest.raises(AssertionError, match="draws_tubes must be True or False; 'no' was given"):
            check_renderer(_ReadsTubes, checks=("tracts",))
    finally:
        _ReadsTubes.draws_tubes = False
    # saying nothing: tubes, as before the capability
    del _ReadsTubes.draws_tubes
    try:
        check_renderer(_ReadsTubes, checks=("tracts",))
    finally:
        _ReadsTubes.draws_tubes = False


def test_a_stand_in_that_draws_tubes_gets_them(tmp_path):
    from brainpainter.atlas.template import load_template
    from brainpainter.rendering.scene import Scene
    from brainpainter.testing.conformance import write_tiny_template
    from brainpainter.testing.stand_in import StandInRenderer
    from brainpainter.testing.tiny_tracts import tiny_tracts

    template = load_template(write_tiny_template(tmp_path / "tiny"))
    for draws, built in ((True, True), (False, False)):
        scene = Scene(template, "dk", layers=(TractLayer(None, (("AF_left", 1),), tracts=tiny_tracts()),))
        r = StandInRenderer.with_(draws_tubes=draws)(scene)
        tract = [p for p in scene.geometry._lazy.entries if p.kind == "tract"]
        assert [p.tubes_built for p in tract] == [built, built]
        assert (r.tube_triangles > 0) is draws
        assert r.tube_triangles == (sum(len(p.triangles) for p in tract) if draws else 0)
