"""Memory per image: painting keeps nothing per image, and the check would see a 0.3 MB-per-image leak.

:func:`brainpainter.testing.growth_per_image` samples resident memory after
every image (after a warm-up) and takes the Theil-Sen slope. Painting through
:class:`~brainpainter.rendering.painter.Painter` (values -> colours -> palette
-> renderer) and encoding the PNG, with the stand-in renderer, must stay under
0.1 MB per image; the same measurement with a stand-in that keeps 0.3 MB per
image must fail, which shows the check can catch a leak of that size
(a fixed allowance of 25 MB over 60 images could not). The Blender
renderer's own check is in test_renderer_blender.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.color.scale import make_scale
from brainpainter.io.output import png_bytes
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import get_view
from brainpainter.testing import StandInRenderer, growth_per_image, stand_in, theil_sen
from brainpainter.testing.memory import can_measure

pytestmark = pytest.mark.skipif(not can_measure(), reason="needs /proc/self/statm (Linux)")
LIMIT_MB = 0.1
N_IMAGES = 150


def per_image_mb(tiny, cls: type[StandInRenderer]) -> float:
    """Resident memory growth per image (MB) of painting and encoding images with renderer `cls`."""
    scale = make_scale(vmin=0, vmax=3)
    views = [get_view(n) for n in ("lateral-left", "medial-right", "subcortical")]
    rng = np.random.default_rng(0)
    with stand_in("memory", cls) as name, Painter("dk", tiny, renderer=name,
                                                   settings=RenderSettings(width=160, height=120)) as painter:
        def one(i: int) -> None:
            values = {"Left-insula": float(rng.random() * 3), "Right-precuneus": float(i % 4)}
            png_bytes(painter.paint(values, views[i % 3], scale))

        return growth_per_image(one, n=N_IMAGES)


#: The stand-in, without its record of calls (which grows by design).
QUIET = StandInRenderer.with_(record=False)


def test_painting_keeps_nothing_per_image(tiny):
    grown = per_image_mb(tiny, QUIET)
    assert grown < LIMIT_MB, f"{grown:.3f} MB per image"


def test_the_check_catches_a_leak_of_0_3_mb_per_image(tiny):
    leaking = QUIET.with_(leak_mb=0.3)
    grown = per_image_mb(tiny, leaking)
    assert grown > LIMIT_MB, f"a 0.3 MB-per-image leak measured as {grown:.3f} MB per image"
    assert 0.2 < grown < 0.45, grown
    leaking.reset()


def test_theil_sen_follows_a_chunked_leak_and_ignores_one_step():
    steps = np.arange(120)
    chunked = 1.0 * (steps // 3)  # the allocator hands out 1 MB every third image: 0.33 MB per image
    assert theil_sen(chunked) == pytest.approx(1 / 3, abs=0.05)
    one_step = np.where(steps < 60, 100.0, 108.0)  # a cache filled once, half-way
    assert theil_sen(one_step) < LIMIT_MB
    spikes = np.zeros(120)
    spikes[::10] = 50.0
    assert theil_sen(spikes) == 0.0
