"""Every registered renderer passes the renderer conformance suite (brainpainter.testing.check_renderer).

Runs without a GPU (the Blender renderer draws through Mesa's llvmpipe where there is none).
"""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.atlas import registry
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
