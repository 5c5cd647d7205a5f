"""The conformance suite's ``connectome`` check: node spheres and edge cylinders drawn where they are.

:func:`tiny_connectome` (two nodes inside the tiny template's hemispheres, one edge) is drawn
from above in flat colours; each node and the edge must show in its exact colour, centred where
the camera projects it, and the node of the larger value must draw more pixels.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .pixels import WHITE, near

RGB = tuple[float, float, float]
#: Colours of the connectome check's two nodes and its edge (none a default colour of the scene).
CONNECTOME_COLORS: dict[str, RGB] = {"node:0": (1.0, 0.6, 0.0), "node:1": (0.0, 0.6, 0.3),
                                     "edge:0": (0.6, 0.0, 1.0)}


def tiny_connectome() -> Any:
    """Two nodes of the tiny template, left (value 1) and right (value 4), and one edge between them.

    Returns
    -------
    brainpainter.connectome.model.Connectome
    """
    from brainpainter.connectome.model import Connectome

    weights = np.array([[np.nan, 0.8], [0.8, np.nan]])
    return Connectome(("left", "right"), np.array([[-35.0, 0.0, 20.0], [35.0, 0.0, 20.0]]), weights,
                      node_values=np.array([1.0, 4.0]))


def connectome_check(run: Any) -> None:
    """Nodes and an edge in exact flat colours, where the camera projects them, through the glass cortex.

    `run` is the conformance suite's run (:func:`brainpainter.testing.conformance.check_renderer`).
    """
    from brainpainter.rendering import framing
    from brainpainter.rendering.connectome_layers import ConnectomeLayer
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import get_view


    width, height = 2 * run.width, 2 * run.height  # a 2 mm node is a few pixels wide at 160 x 120
    settings = RenderSettings(width=width, height=height, quality="fast", shading="flat",
                              glass_opacity=0.0, background=WHITE)
    scene = Scene(run.template, "dk", settings=settings, layers=(ConnectomeLayer(tiny_connectome()),))
    view = get_view("dorsal")
    renderer = run.cls(scene)
    try:
        img = np.asarray(renderer.render(Palette(CONNECTOME_COLORS, scene.geometry), view))
    finally:
        renderer.close()
    pose = scene.geometry.camera(view, width / height)
    counts = {}
    worst = 0.0
    for key, rgb in CONNECTOME_COLORS.items():
        mask = near(img, rgb, 1)
        counts[key] = int(mask.sum())
        if mask.sum() < 10:
            run.problems.append(f"connectome: dorsal: {key} is not drawn in its flat colour {rgb}")
            continue
        kind = key.partition(":")[0]
        slot = scene.geometry.slot_of[key]
        part = next(p for p in scene.geometry.parts if p.kind == kind and (p.palette_index == slot).any())
        expected = framing.to_pixels(part.vertices[part.palette_index == slot], pose, width,
                                     height).mean(axis=0)
        ys, xs = np.nonzero(mask)
        err = float(np.hypot(xs.mean() + 0.5 - expected[0], ys.mean() + 0.5 - expected[1]))
        worst = max(worst, err)
        if err > 0.05 * width:
            run.problems.append(f"connectome: dorsal: {key} is centred {err:.1f} px from where the camera "
                                "puts it")
    run.report["connectome_worst_px"] = round(worst, 2)
    run.report["connectome_pixels"] = counts
    if counts["node:1"] <= counts["node:0"]:
        run.problems.append(f"connectome: the larger node (value 4) draws {counts['node:1']} pixels, the "
                            f"smaller (value 1) {counts['node:0']}; node radii must be drawn")
