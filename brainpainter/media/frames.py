"""Movie frames: the views side by side, then the caption, a timeline with the key frames, the colour bar.

An optional orbit turns the camera around the vertical axis over the movie,
with a fixed image scale (the brain does not grow or shrink as it turns).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.color.scale import ColourScale
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.views import View


# -- orbit -----------------------------------------------------------------------------
def orbit_views(painter: Painter, view: View, azimuths: Sequence[float], aspect: float) -> list[View]:
    """`view` turned to each azimuth, zoomed so the image scale stays that of the widest direction."""
    from brainpainter.rendering.framing import extent

    # the hull points the camera frames (brainpainter.rendering.geometry), so the orbit and each image agree
    points = painter.scene.geometry.view_points(view)
    extents = [extent(points, az, view.elevation, aspect) for az in azimuths]
    widest = max((e for e in extents if e), default=None)
    out = []
    for az, e in zip(azimuths, extents, strict=True):
        zoom = view.zoom * (e / widest if e and widest else 1.0)
        out.append(replace(view, azimuth=float(az) % 360.0, zoom=zoom))
    return out


def sweep_views(painter: Painter, views: list[View], spec: str) -> list[View]:
    """`views` (one per frame) each cut by a plane that sweeps across the brain over the frames
    (``--clip-sweep x``: ``x<v``, v from the brain's left edge to just short of its right one, so the
    last frame keeps a slice)."""
    from brainpainter.rendering.clip import AXES, ClipPlane, parse_sweep

    axis, side = parse_sweep(spec)
    along = painter.scene.geometry.view_points(views[0])[:, AXES.index(axis)]
    lo, hi, n = float(along.min()), float(along.max()), len(views)
    out = []
    for i, view in enumerate(views):
        at = lo + (hi - lo) * i / n if side == "<" else hi - (hi - lo) * i / n
        out.append(replace(view, clip=(*view.clip, ClipPlane(axis, side, round(at, 3)))))
    return out


# -- frame composition ------------------------------------------------------------------
def _font(size: int) -> Any:
    """DejaVu Sans (shipped with matplotlib) at `size` pixels."""
    from matplotlib import font_manager
    from PIL import ImageFont

    path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans"))
    return ImageFont.truetype(path, max(6, int(size)))


def _over(rgba: NDArray[Any], bg: NDArray[Any]) -> NDArray[Any]:
    """Composite RGBA uint8 over an RGB background colour; returns RGB uint8."""
    if rgba.shape[-1] == 3:
        return rgba
    a = rgba[..., 3:4].astype(np.float32) / 255.0
    out = rgba[..., :3].astype(np.float32) * a + bg.astype(np.float32) * (1.0 - a)
    return np.round(out).astype(np.uint8)


class FrameComposer:
    """Lays out movie frames: views side by side, then caption, timeline and colour bar.

    Parameters
    ----------
    n_views : int
    size : (int, int)
        Width and height of one render.
    scale : ColourScale
    key_clock : sequence of float
        Key-frame times (for the timeline's marks).
    background : colour
    label, ticks, nan, missing
        For the colour bar.
    title : str, optional
        A line above the views.
    more_bars : sequence of (ColourScale, str)
        Colour bars of further layers and their labels, one under the other below the first.
    """

    def __init__(self, n_views: int, size: tuple[int, int], scale: ColourScale, key_clock: Sequence[float],
                 *, background: ColorLike = "white", label: str | None = None,
                 ticks: Sequence[float] | str | None = None, nan: bool = False, missing: bool = False,
                 title: str | None = None, more_bars: Sequence[tuple[ColourScale, str]] = ()) -> None:
        from brainpainter.media.colorbar import colorbar_height, colorbar_image, text_color

        w, h = size
        self.n_views, self.w, self.h = n_views, w, h
        width = n_views * w
        u = max(0.45, min(h / 600.0, width / 800.0))
        self.u = u
        self.bg = np.round(np.array(to_rgb(background)) * 255).astype(np.uint8)
        self.fg = (0, 0, 0) if text_color(background) == "black" else (255, 255, 255)
        self.key_clock = [float(t) for t in key_clock]
        pad = max(6, round(16 * u))
        self.pad = pad
        self.caption_font = _font(round(30 * u))
        self.title_font = _font(round(32 * u))
        self.header = round(52 * u) if title else 0
        cb_w = min(width - 2 * pad, max(round(520 * u), 240))
        side = width >= cb_w + max(round(360 * u), 200) + 3 * pad
        fontsize = max(6.0, 16.0 * u)
        first: dict[str, Any] = {"label": label, "ticks": ticks, "nan": nan, "missing": missing,
                                 "fontsize": fontsize}
        bars: list[tuple[ColourScale, dict[str, Any]]] = [
            (scale, first), *((s, {"label": lb, "fontsize": fontsize}) for s, lb in more_bars)]
        bar_h = [max(56, round(110 * u), math.ceil(colorbar_height(s, cb_w / 100.0, **args) * 100))
                 for s, args in bars]
        cb_h = sum(bar_h)
        cb_h += cb_h % 2
        caption_h = round(92 * u)
        footer = max(cb_h, caption_h) if side else cb_h + caption_h
        height = self.header + h + footer
        self.size = (width + width % 2, height + height % 2)
        W, H = self.size
        canvas = np.empty((H, W, 3), np.uint8)
        canvas[:] = self.bg
        y0 = self.header + h + (footer - cb_h if side else caption_h)
        x0 = W - cb_w - pad if side else (W - cb_w) // 2
        for (s, args), bh in zip(bars, bar_h, strict=True):  # one bar per scaled layer, one under the other
            cb = colorbar_image(s, (cb_w, bh), background=background, **args)
            canvas[y0:y0 + bh, x0:x0 + cb_w] = _over(cb, self.bg)
            y0 += bh
        self.caption_box = (pad, self.header + h, (x0 - pad) if side else (W - pad),
                            self.header + h + caption_h)
        if title:
            from PIL import Image, ImageDraw

            im = Image.fromarray(canvas)
            ImageDraw.Draw(im).text((W / 2, self.header / 2 + round(4 * u)), title, fill=self.fg,
                                    font=self.title_font, anchor="mm")
            canvas = np.asarray(im).copy()
        self.canvas = canvas

    def compose(self, renders: Sequence[NDArray[Any]], caption: str, clock: float) -> NDArray[Any]:
        """One frame, RGB uint8 of shape (height, width, 3) (both even)."""
        from PIL import Image, ImageDraw

        frame = self.canvas.copy()
        for k, img in enumerate(renders):
            frame[self.header:self.header + self.h, k * self.w:(k + 1) * self.w] = _over(img, self.bg)
        x0, y0, x1, _ = self.caption_box
        im = Image.fromarray(frame)
        draw = ImageDraw.Draw(im)
        u = self.u
        draw.text((x0, y0 + round(14 * u)), caption, fill=self.fg, font=self.caption_font, anchor="la")
        # timeline: a track, the part done, key-frame marks and the current position
        ty = y0 + round(66 * u)
        lo, hi = self.key_clock[0], self.key_clock[-1]
        tx0, tx1 = x0 + round(6 * u), max(x0 + round(6 * u) + 10, x1 - round(10 * u))

        def x_of(c: float) -> float:
            return tx0 + (tx1 - tx0) * (c - lo) / (hi - lo)

        grey = tuple(int(0.5 * a + 0.5 * b) for a, b in zip(self.fg, self.bg.tolist(), strict=True))
        lw = max(2, round(4 * u))
        draw.line((tx0, ty, tx1, ty), fill=grey, width=lw)
        draw.line((tx0, ty, x_of(clock), ty), fill=self.fg, width=lw)
        mark = max(3, round(7 * u))
        for c in self.key_clock:
            x = x_of(c)
            draw.line((x, ty - mark, x, ty + mark), fill=self.fg if c <= clock else grey,
                      width=max(1, lw // 2))
        r = max(3, round(8 * u))
        x = x_of(clock)
        draw.ellipse((x - r, ty - r, x + r, ty + r), fill=self.fg)
        return np.asarray(im)
