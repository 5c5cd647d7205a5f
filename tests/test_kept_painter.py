"""A figure's painter kept for the next figure of the same scene (rendering/kept.py, issue 45's cost):
one scene loaded for figures of one scene, a new one for another scene, the same pixels as a fresh one."""

from __future__ import annotations

import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.rendering import kept
from brainpainter.testing import StandInRenderer, stand_in

VALUES = {"Left-insula": 3.0, "Left-precuneus": 1.0, "Left-superiorfrontal": 0.0}


@pytest.fixture(autouse=True)
def released():
    kept.release()
    yield
    kept.release()


def _figure(tiny, renderer, values=VALUES, **kw):
    kw = {"views": "lateral-left", **kw}
    return brainpainter.figure(values, "dk", template=tiny, renderer=renderer, width=40, height=30,
                               progress=False, **kw)


def test_figures_of_one_scene_load_it_once_and_another_scene_replaces_it(tiny):
    with stand_in("kept-counting") as name:
        _figure(tiny, name)
        _figure(tiny, name, values={"Left-insula": 1.0})  # other values, the same scene
        assert StandInRenderer.scenes == 1
        _figure(tiny, name, background="black")  # other settings: another scene, the first closed
        assert StandInRenderer.scenes == 2
        (painter,) = kept._KEPT.values()
        assert painter._renderer is not None  # the last stays loaded for the next figure
        _figure(tiny, name, jobs=2)  # not serial: its own painter, the kept one untouched
        assert kept.is_kept(painter)
        kept.release()
        assert painter._renderer is None and not kept._KEPT


def test_a_figure_that_fails_to_render_leaves_no_painter_kept(tiny):
    def fail_after_one(n: int) -> BaseException | None:
        return BrainPainterError("stand-in renderer failed on purpose") if n > 1 else None

    with stand_in("kept-failing", StandInRenderer.with_(fail=fail_after_one)) as name:
        with pytest.raises(BrainPainterError, match="on purpose"):
            _figure(tiny, name, views="lateral-left,medial-left")
    assert not kept._KEPT


@pytest.mark.render
def test_the_kept_renderer_draws_the_pixels_of_a_fresh_one(tiny):
    pytest.importorskip("bpy")
    kw = {"views": "lateral-left,dorsal", "width": 160, "height": 120, "quality": "fast"}
    fresh = brainpainter.figure(VALUES, "dk", template=tiny, progress=False, **kw)
    again = brainpainter.figure({"Left-insula": 1.0}, "dk", template=tiny, progress=False, **kw)
    warm = brainpainter.figure(VALUES, "dk", template=tiny, progress=False, **kw)
    assert len(kept._KEPT) == 1
    for key, pixels in fresh.images.items():
        np.testing.assert_array_equal(pixels, warm.images[key])
        assert not np.array_equal(pixels, again.images[key])  # the values changed, not the scene


def test_a_figure_made_while_the_kept_painter_draws_another_draws_with_its_own(tiny):
    with stand_in("kept-busy") as name:
        first = brainpainter.Painter("dk", tiny, renderer=name)
        second = brainpainter.Painter("dk", tiny, renderer=name)  # the same scene
        assert kept.kept_painter(first) is first  # kept, and in use until put back
        assert kept.kept_painter(second) is second and not kept.is_kept(second)  # meanwhile: its own
        kept.put_back(first)
        third = brainpainter.Painter("dk", tiny, renderer=name)
        assert kept.kept_painter(third) is first  # put back: the next figure draws with it
        kept.put_back(first)
        _figure(tiny, name)  # a figure that fails before it renders leaves nothing in use
        with pytest.raises(BrainPainterError):
            _figure(tiny, name, views="no-such-view")
        assert not kept._IN_USE
