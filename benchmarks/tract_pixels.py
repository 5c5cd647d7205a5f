"""Tract images before and after a change to the tubes: render a fixed set, then compare two sets.

``render DIR`` draws ``bench_tracts.write_tractogram``'s synthetic bundles
(``--streamlines``, default 10,000) at 1200x900 from ``subcortical``,
``lateral-left`` and ``subcortical-dorsal``, in direction colours and with one
value per bundle, as PNGs in DIR. ``compare A B OUT`` prints the mean absolute
difference per image (RGB units 0-255, over pixels drawn in either) and the
share of pixels that differ by more than 32, and writes A and B side by side
(and a zoomed crop) into OUT to look at.

    python benchmarks/tract_pixels.py render /tmp/before      # on the old code
    python benchmarks/tract_pixels.py render /tmp/after       # on the new code
    python benchmarks/tract_pixels.py compare /tmp/before /tmp/after /tmp/side
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from bench_tracts import BUNDLES, write_tractogram
from PIL import Image

VIEWS = ("subcortical", "lateral-left", "subcortical-dorsal")


def render(out: Path, n: int) -> None:
    from brainpainter.color.scale import make_scale
    from brainpainter.io.output import png_bytes
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.tract_parts import TractLayer
    from brainpainter.rendering.views import get_view
    from brainpainter.tracts.model import TractSpec

    out.mkdir(parents=True, exist_ok=True)
    settings = RenderSettings(width=1200, height=900)
    values = np.linspace(0.0, 1.0, len(BUNDLES))
    scale = make_scale(values)
    with tempfile.TemporaryDirectory() as tmp:
        folder = write_tractogram(Path(tmp) / "bundles", n)
        spec = TractSpec((str(folder),), max_streamlines=n)
        for label, nodes in (("direction", ()), ("values", tuple((b, 1) for b in BUNDLES))):
            with Painter("dk", settings=settings, layers=(TractLayer(spec, nodes),)) as painter:
                colors = {f"tract:{b}": tuple(float(c) for c in scale(v)[:3])
                          for b, v in zip(BUNDLES, values, strict=True)} if nodes else {}
                for view in VIEWS:
                    img = painter.paint_colors(colors, get_view(view))
                    (out / f"{label}-{view}.png").write_bytes(png_bytes(img))
                    print(out / f"{label}-{view}.png", flush=True)


def compare(a: Path, b: Path, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for pa in sorted(a.glob("*.png")):
        x = np.asarray(Image.open(pa).convert("RGBA"), np.int16)
        y = np.asarray(Image.open(b / pa.name).convert("RGBA"), np.int16)
        drawn = (x[..., 3] > 0) | (y[..., 3] > 0)
        diff = np.abs(x[..., :3] - y[..., :3]).max(axis=-1)[drawn]
        print(f"{pa.name:32s} mean |diff| {np.abs(x[..., :3] - y[..., :3])[drawn].mean():5.2f} RGB units, "
              f"{(diff > 32).mean() * 100:5.2f} % of drawn pixels off by > 32")
        side = np.concatenate([x, y], axis=1).astype(np.uint8)
        Image.fromarray(side).save(out / f"side-{pa.name}")
        h, w = x.shape[:2]
        crop = (slice(h // 3, h // 3 + 300), slice(w // 3, w // 3 + 400))
        zoom = np.concatenate([x[crop], y[crop]], axis=1).astype(np.uint8)
        Image.fromarray(zoom).resize((zoom.shape[1] * 2, zoom.shape[0] * 2), Image.NEAREST).save(
            out / f"zoom-{pa.name}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("out", type=Path)
    r.add_argument("--streamlines", type=int, default=10000)
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    c.add_argument("out", type=Path)
    args = p.parse_args()
    if args.cmd == "render":
        render(args.out, args.streamlines)
    else:
        compare(args.a, args.b, args.out)


if __name__ == "__main__":
    main()
