"""Smoothness of region borders: a flat-shaded two-colour DK render at 2400x1800.

Every cortical region of the atlas gets one of two colours (alternating in
atlas order); the lateral-left view is rendered with ``--shading flat`` and
:func:`brainpainter.media.imagemetrics.border_ratio` divides the length of the
borders between the two colours by their length after a 1.5 px Gaussian
smoothing. Target (issue 10): <= 1.09 for the built-in atlases.

    python benchmarks/border_smoothness.py [--atlas dk] [--template fsaverage] [--save out.png]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

#: The two region colours (sRGB 0-255).
COLOR_A = (230, 60, 40)
COLOR_B = (40, 90, 220)


def two_colour_render(atlas: str = "dk", template: str = "fsaverage", view: str = "lateral-left",
                      width: int = 2400, height: int = 1800, renderer: str = "blender") -> np.ndarray:
    """Flat-shaded render with the atlas's cortical regions in `COLOR_A` / `COLOR_B`; RGBA (h, w, 4)."""
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.scene import RenderSettings
    from brainpainter.rendering.views import get_view

    settings = RenderSettings(width=width, height=height, shading="flat")
    with Painter(atlas, template, settings=settings, renderer=renderer) as painter:
        cortical = [r.key for r in painter.atlas.regions if r.kind == "cortical"]
        colors = {k: tuple(c / 255 for c in (COLOR_A if i % 2 == 0 else COLOR_B))
                  for i, k in enumerate(cortical)}
        return painter.paint_colors(colors, get_view(view))


def main() -> None:
    from brainpainter.media.imagemetrics import border_ratio

    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--atlas", default="dk")
    parser.add_argument("--template", default="fsaverage")
    parser.add_argument("--views", default="lateral-left")
    parser.add_argument("--size", default="2400x1800")
    parser.add_argument("--save", type=Path, default=None, help="save the render(s) here (a folder)")
    args = parser.parse_args()
    w, h = (int(x) for x in args.size.split("x"))
    for view in args.views.split(","):
        t0 = time.perf_counter()
        img = two_colour_render(args.atlas, args.template, view, w, h)
        ratio, length = border_ratio(img, COLOR_A, COLOR_B)
        print(f"{args.atlas} {view} {w}x{h}: border ratio {ratio:.4f} (border {length:.0f} px), "
              f"{time.perf_counter() - t0:.1f} s")
        if args.save:
            from PIL import Image

            args.save.mkdir(parents=True, exist_ok=True)
            Image.fromarray(img).save(args.save / f"{args.atlas}_{view}.png")


if __name__ == "__main__":
    main()
