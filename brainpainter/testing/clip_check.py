"""The conformance suite's ``clip`` check: a cutaway removes the cortex on its side, caps the cut and shows
what lies inside.

The tiny template's left hemisphere (a sphere of radius 50 mm at x = -60) is cut at x = -60 and seen from
the left in flat colours (a cortex view of both hemispheres with ``View.clip``): none of its regions'
colours may remain where the plane removed them, its cut face must be drawn closed in
:data:`~brainpainter.rendering.clip.CAP_COLOR`, and the ``Left-Hippocampus`` box inside it (x = -20) must
show in its colour, where the camera projects it; without the clip the box is hidden.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .pixels import COLORS, WHITE, near

RGB = tuple[float, float, float]


def clip_check(run: Any) -> None:
    """The cutaway check (module docstring); `run`: the suite's run
    (:func:`brainpainter.testing.conformance.check_renderer`)."""
    from brainpainter.rendering import framing
    from brainpainter.rendering.clip import CAP_COLOR, ClipPlane
    from brainpainter.rendering.views import View

    cut = View("cutaway-tiny", "cortex", ("lh", "rh"), 180.0, 0.0, clip=(ClipPlane("x", "<", -60.0),))
    whole = View("cutaway-tiny", "cortex", ("lh", "rh"), 180.0, 0.0)
    scene, renderer = run.make(quality="fast", shading="flat", glass_opacity=0.0, background=WHITE)
    try:
        img, ref = run.paint(scene, renderer, COLORS, cut), run.paint(scene, renderer, COLORS, whole)
    finally:
        renderer.close()
    left = [rgb for key, rgb in COLORS.items() if key.startswith("Left-") and key != "Left-Hippocampus"]
    before, after = (sum(int(near(im, rgb, 1).sum()) for rgb in left) for im in (ref, img))
    inside, hidden = int(near(img, COLORS["Left-Hippocampus"], 1).sum()), int(
        near(ref, COLORS["Left-Hippocampus"], 1).sum())
    cap = int(near(img, CAP_COLOR, 2).sum())
    run.report["clip_pixels"] = {"left_cortex_before": before, "left_cortex_after": after, "cap": cap,
                                 "inside": inside}
    if after > 0.02 * max(before, 1):
        run.problems.append(f"clip: the cut left {after} pixels of the removed cortex's colours ({before} "
                            "uncut)")
    if cap < 0.05 * run.width * run.height:
        run.problems.append(f"clip: the cut face is not drawn closed in {CAP_COLOR} ({cap} pixels)")
    if hidden or inside < 20:
        run.problems.append(f"clip: the structure inside shows in {inside} pixels cut and {hidden} uncut")
        return
    part = next(p for p in scene.geometry.visible(cut) if p.kind == "subcortical")
    slot = scene.geometry.slot_of["Left-Hippocampus"]
    pose = scene.geometry.camera(cut, run.width / run.height)
    expected = framing.to_pixels(part.vertices[part.palette_index == slot], pose, run.width,
                                 run.height).mean(axis=0)
    ys, xs = np.nonzero(near(img, COLORS["Left-Hippocampus"], 1))
    err = float(np.hypot(xs.mean() + 0.5 - expected[0], ys.mean() + 0.5 - expected[1]))
    run.report["clip_inside_px"] = round(err, 2)
    if err > 0.05 * run.width:
        run.problems.append(f"clip: the structure inside is {err:.1f} px from where the camera puts it")
