"""How full the image is: the camera fits a view's projected extent to the image's aspect (whichever of
width and height binds, MARGIN on each side), for any brain. The human template's cameras are pinned
(a framing change must be deliberate), and the mouse's views are measured on rendered pixels at the default
1200x900 in tests/test_mouse_plugin.py."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.rendering import framing
from brainpainter.rendering.painter import load_scene
from brainpainter.rendering.views import PRESETS

# ortho_scale and camera location (mm) of every preset of the default template (dk on fsaverage) at
# 1200x900, as framed since the views were added: a change here changes every human render
HUMAN_1200x900 = {
    "lateral-left": (187.692, (-139.371, -17.932, 15.488)),
    "medial-left": (187.692, (72.36, -17.932, 15.488)),
    "lateral-right": (186.797, (140.853, -17.153, 15.566)),
    "medial-right": (186.797, (-71.747, -17.153, 15.566)),
    "dorsal": (250.781, (0.596, -17.75, 205.757)),
    "ventral": (250.781, (0.596, -17.75, -174.625)),
    "anterior": (182.583, (0.596, 243.48, 15.566)),
    "posterior": (182.583, (0.596, -278.979, 15.566)),
    "subcortical": (212.001, (-127.568, 34.493, 59.264)),
    "subcortical-left": (215.608, (-176.981, -16.877, 5.351)),
    "subcortical-dorsal": (254.367, (1.021, -17.495, 229.943)),
    "subcortical-ventral": (254.367, (1.021, -17.495, -219.241)),
}


@pytest.fixture(scope="module")
def human():
    return load_scene("dk")[1].geometry


def test_human_framing_is_unchanged(human):
    for name, (scale, location) in HUMAN_1200x900.items():
        pose = human.camera(PRESETS[name], 1200 / 900)
        assert pose.ortho_scale == pytest.approx(scale, abs=2e-3), name
        np.testing.assert_allclose(pose.location, location, atol=2e-3, err_msg=name)


@pytest.mark.parametrize("size", [(1200, 900), (900, 900), (600, 1000)])
def test_the_binding_side_fills_the_image_less_the_margin_and_the_brain_is_centred(human, size):
    w, h = size
    fill = 1 / (1 + 2 * framing.MARGIN)
    for view in PRESETS.values():
        hull = np.vstack([p.hull for p in human.visible(view)])
        px = framing.to_pixels(hull, human.camera(view, w / h), w, h)
        fw, fh = np.ptp(px[:, 0]) / w, np.ptp(px[:, 1]) / h
        assert max(fw, fh) == pytest.approx(fill, abs=1e-6), view.name  # whichever binds
        assert fw <= fill + 1e-6 and fh <= fill + 1e-6, view.name
        centre = (px.min(axis=0) + px.max(axis=0)) / 2
        np.testing.assert_allclose(centre, (w / 2, h / 2), atol=1e-6 * max(w, h), err_msg=view.name)


def test_a_long_narrow_brain_fills_the_side_that_binds():
    # a box 8 wide (x), 16 long (y), 6 high (z): from above it binds on the image height at 4:3
    box = np.array([[x, y, z] for x in (-4, 4) for y in (-8, 8) for z in (-3, 3)], float)
    pose = framing.frame(box, 0.0, 90.0, 1.0, 4 / 3)
    px = framing.to_pixels(box, pose, 1200, 900)
    assert np.ptp(px[:, 1]) / 900 == pytest.approx(1 / 1.08)
    assert np.ptp(px[:, 0]) / 1200 == pytest.approx(8 / 16 * 900 / 1200 / 1.08)  # width: what is left
    pose = framing.frame(box, 180.0, 0.0, 1.0, 4 / 3)  # from the left: the length binds on the width
    assert np.ptp(framing.to_pixels(box, pose, 1200, 900)[:, 0]) / 1200 == pytest.approx(1 / 1.08)
