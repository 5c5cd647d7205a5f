"""Before/after images of the lighting presets (issue 25), and the relief numbers behind them.

Render a set with one checkout, render it again with another, then put the two
side by side::

    # "before": a Python whose brainpainter is the previous release (e.g. main's editable install)
    python benchmarks/lighting_gallery.py render /tmp/gallery-before
    # "after": this checkout
    python benchmarks/lighting_gallery.py render /tmp/gallery-after
    python benchmarks/lighting_gallery.py compare /tmp/gallery-before /tmp/gallery-after docs/lighting

``render`` writes, per lighting preset (``studio``, ``soft``, ``sulc``,
``flat-studio``) and ``--shading flat``: the lateral-left view with every DK
region white, pure red, and coloured by random values through viridis, and the
``subcortical`` view; plus ``relief.json`` with the CIE L* spread (p90 - p10
of brain pixels, :func:`brainpainter.media.imagemetrics.lightness_spread`) and
the median colours. ``compare`` writes one small PNG per preset: before on top,
after below.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

PRESETS = ("studio", "soft", "sulc", "flat-studio", "flat")
FILLS = {"white": (1.0, 1.0, 1.0), "red": (1.0, 0.0, 0.0), "yellow": (1.0, 1.0, 0.0)}


def _lightness_spread(image: np.ndarray) -> float:
    """L* p90 - p10 of the non-white pixels (for releases without imagemetrics.lightness_spread)."""
    rgb = image[..., :3][~np.all(image[..., :3] == 255, axis=-1)] / 255.0
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    y = lin @ np.array([0.2126, 0.7152, 0.0722])
    lstar = np.where(y > (6 / 29) ** 3, 116.0 * np.cbrt(y) - 16.0, y * (29 / 3) ** 3)
    p10, p90 = np.percentile(lstar, [10, 90])
    return float(p90 - p10)


def render(out: Path, width: int = 800, height: int = 600) -> dict[str, dict[str, object]]:
    """Render the gallery into `out`; returns the relief numbers (also written to ``relief.json``)."""
    from matplotlib import colormaps
    from PIL import Image

    try:
        from brainpainter.media.imagemetrics import lightness_spread
    except ImportError:  # a release before issue 25
        lightness_spread = _lightness_spread
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.scene import RenderSettings
    from brainpainter.rendering.views import get_view

    out.mkdir(parents=True, exist_ok=True)
    numbers: dict[str, dict[str, object]] = {}
    rng = np.random.default_rng(25)
    for preset in PRESETS:
        settings = (RenderSettings(width, height, shading="flat") if preset == "flat"
                    else RenderSettings(width, height, lighting=preset))
        with Painter("dk", settings=settings) as painter:
            keys = [r.key for r in painter.atlas.regions if r.kind == "cortical"]
            sub = [r.key for r in painter.atlas.regions if r.kind != "cortical"]
            values = rng.random(len(keys) + len(sub))
            viridis = colormaps["viridis"]
            colours = {k: tuple(float(c) for c in viridis(v)[:3])
                       for k, v in zip(keys + sub, values, strict=True)}
            row: dict[str, object] = {}
            for name, fill in FILLS.items():
                img = painter.paint_colors(dict.fromkeys(keys, fill), get_view("lateral-left"))
                Image.fromarray(img).save(out / f"{preset}_{name}.png")
                brain = img[..., :3][~np.all(img[..., :3] == 255, axis=-1)]
                row[name] = {"L*_spread": round(lightness_spread(img), 1),
                             "median_rgb": np.median(brain, axis=0).tolist()}
            Image.fromarray(painter.paint_colors(colours, get_view("lateral-left"))).save(
                out / f"{preset}_viridis.png")
            Image.fromarray(painter.paint_colors(colours, get_view("subcortical"))).save(
                out / f"{preset}_subcortical.png")
            numbers[preset] = row
            print(preset, json.dumps(row))
    (out / "relief.json").write_text(json.dumps(numbers, indent=1), encoding="utf-8")
    return numbers


def compare(before: Path, after: Path, out: Path, tile: int = 200) -> None:
    """One PNG per preset: the images of `before` on the top row, those of `after` below."""
    from PIL import Image, ImageDraw

    out.mkdir(parents=True, exist_ok=True)
    kinds = (*FILLS, "viridis", "subcortical")
    for preset in PRESETS:
        h = tile * 3 // 4
        sheet = Image.new("RGB", (tile * len(kinds) + 60, 2 * h), "white")
        draw = ImageDraw.Draw(sheet)
        for r, (label, folder) in enumerate((("before", before), ("after", after))):
            draw.text((4, r * h + h // 2), label, fill="black")
            for c, kind in enumerate(kinds):
                src = folder / f"{preset}_{kind}.png"
                if src.is_file():
                    im = Image.open(src).convert("RGB")
                    im.thumbnail((tile, h))
                    sheet.paste(im, (60 + c * tile, r * h))
        # full colour: a 256-colour palette tints the grey shading
        sheet.save(out / f"lighting-{preset}.png", optimize=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("out", type=Path)
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    c.add_argument("out", type=Path)
    args = parser.parse_args()
    if args.cmd == "render":
        render(args.out)
    else:
        compare(args.before, args.after, args.out)


if __name__ == "__main__":
    main()
