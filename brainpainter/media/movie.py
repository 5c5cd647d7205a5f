"""Movies of a progression: key frames from table rows, interpolated in between.

Rows of the table are key frames, in table order or sorted by a numeric
``time_column``. Between consecutive key frames the values are interpolated
over ``frames_per_step`` frames, linearly or with smooth easing (smoothstep:
slow out of one key frame, slow into the next). A region that is NaN (no
data) in either of two key frames is NaN between them; regions without a
column keep the missing colour. One colour scale, computed from all rows, is
fixed for the whole movie.

Each frame shows the views side by side, and under them the stage (or time)
caption, a timeline with the key frames marked, and the colour bar. Frames
are re-colourings of one loaded scene (:class:`~brainpainter.rendering.painter.Painter`).
An optional orbit turns the camera around the vertical axis over the movie,
with a fixed image scale (the brain does not grow or shrink as it turns).

MP4 is H.264 (yuv420p, BT.709, ``+faststart``) through the ffmpeg binary of
the ``imageio-ffmpeg`` wheel; GIF is written with pillow. The movie is
written to a temporary file in the output folder and renamed when complete,
so a failure or Ctrl-C leaves no partial file.

>>> from brainpainter.media.movie import make_movie
>>> make_movie("examples/brainpainter_dk.csv", atlas="dk", out="progression.mp4",
...            views="lateral-left,medial-left", frames_per_step=24)   # doctest: +SKIP
"""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.color.scale import DEFAULT_MISSING_COLOR, DEFAULT_NAN_COLOR, ColourScale
from brainpainter.errors import BrainPainterError, choice_error, nearest

if TYPE_CHECKING:  # pragma: no cover
    from brainpainter.atlas.model import Atlas
    from brainpainter.atlas.template import Template
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.views import View
    from brainpainter.table.region_table import RegionTable

MOVIE_FORMATS = (".mp4", ".gif")
EASINGS = ("linear", "smooth")
MAX_FRAMES = 20_000  # frames of one movie (MP4); GIFs: MAX_GIF_FRAMES
MAX_GIF_FRAMES = 2_000  # a GIF is for slides and web pages; longer movies: MP4
GIF_PALETTE_FRAMES = 12  # frames sampled for a GIF's palette
MAX_FRAME_PIXELS = 8192 * 8192
ARROW = "\u2192"


# -- timing ------------------------------------------------------------------------
def ease(t: np.ndarray | float, easing: str = "linear") -> np.ndarray | float:
    """Map the fraction `t` in [0, 1] of a step to the interpolation weight.

    ``linear``: t; ``smooth``: smoothstep ``3t^2 - 2t^3`` (zero speed at both
    key frames, so each stage is held a moment).
    """
    if easing == "linear":
        return t
    if easing == "smooth":
        return t * t * (3.0 - 2.0 * t)
    raise choice_error("easing", easing, EASINGS)


@dataclass(frozen=True)
class FramePlan:
    """One frame of the movie.

    Attributes
    ----------
    a, b : int
        Key frames (positions in the sorted key list) the frame lies between;
        ``a == b`` at (or while holding) a key frame.
    weight : float
        Interpolation weight of key `b`, after easing, in [0, 1].
    clock : float
        Where the frame is on the time axis (the time column, or the key
        position 0, 1, ... without one), linear in the frame index.
    """

    a: int
    b: int
    weight: float
    clock: float


def plan_frames(times: Sequence[float], frames_per_step: int, easing: str = "linear",
                hold: int = 0, proportional: bool = False) -> list[FramePlan]:
    """Frames of a movie through key frames at `times`.

    Parameters
    ----------
    times : sequence of float, increasing
        Key-frame times.
    frames_per_step : int
        Frames from one key frame to the next (the key frame itself counts,
        the next does not). Total without holds: ``(n_keys - 1) * N + 1``.
    easing : {"linear", "smooth"}
    hold : int
        Extra frames that repeat each key frame.
    proportional : bool
        Give each step frames in proportion to its time gap (``N`` per step on
        average, at least 1), so the clock runs at a steady pace.

    Returns
    -------
    list of FramePlan
    """
    times = [float(t) for t in times]
    k = len(times)
    if k < 2:
        raise BrainPainterError(f"a movie needs at least 2 key frames; {k} was given.")
    if not 1 <= frames_per_step <= MAX_FRAMES:
        raise BrainPainterError(f"frames per step must be between 1 and {MAX_FRAMES}; "
                                f"{frames_per_step} was given.")
    if hold < 0:
        raise BrainPainterError(f"hold must be 0 or more frames; {hold} was given.")
    ease(0.0, easing)  # validates the name
    gaps = np.diff(times)
    if proportional:
        counts = [max(1, round(frames_per_step * (k - 1) * g / gaps.sum())) for g in gaps]
    else:
        counts = [frames_per_step] * (k - 1)
    plan: list[FramePlan] = []
    for s, n in enumerate(counts):
        plan.extend([FramePlan(s, s, 0.0, times[s])] * (1 + hold))
        for j in range(1, n):
            f = j / n
            plan.append(FramePlan(s, s + 1, float(ease(f, easing)), times[s] + f * (times[s + 1] - times[s])))
    plan.extend([FramePlan(k - 1, k - 1, 0.0, times[-1])] * (1 + hold))
    if len(plan) > MAX_FRAMES:
        raise BrainPainterError(f"the movie would have {len(plan)} frames; at most {MAX_FRAMES} are made. "
                                "Lower --frames-per-step or --hold.")
    return plan


def interpolate(a: np.ndarray, b: np.ndarray, weight: float) -> np.ndarray:
    """Values between two key frames: ``(1 - w) a + w b``.

    NaN in either key frame gives NaN strictly between them; at ``w = 0``
    and ``w = 1`` the key frame's own values are returned.

    Parameters
    ----------
    a, b : ndarray of float, shape (n_regions,)
    weight : float in [0, 1]
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if weight <= 0.0:
        return a.copy()
    if weight >= 1.0:
        return b.copy()
    return (1.0 - weight) * a + weight * b  # NaN propagates


def format_clock(value: float, keys: Sequence[float]) -> str:
    """The time shown in captions: as many decimals as the keys use (at least 1, at most 3)."""
    decimals = 1
    for t in keys:
        text = f"{t:.6g}"
        if "." in text and "e" not in text:
            decimals = max(decimals, len(text.split(".")[1]))
    return f"{value:.{min(decimals, 3)}f}"


# -- time column ---------------------------------------------------------------------
def read_times(data: Any, table: RegionTable, time_column: str) -> tuple[str, dict[str, float]]:
    """The times of the images, from the column `time_column` of the input(s).

    Works for wide tables (one row per image) and long tables with an image
    column (the time must be the same on all rows of an image).

    Returns
    -------
    name : str
        The column's name as spelled in the input (it was matched case-insensitively).
    times : dict of str to float
        ``{image name: time}``.
    """
    from brainpainter.io.readers import read_raw
    from brainpainter.table.cells import to_number
    from brainpainter.table.shape import detect_shape, find_column

    inputs = list(data) if isinstance(data, list | tuple) else [data]
    regions = {n.name for n in table.names if n.status == "region"}
    others: list[str] = []
    sources: list[str] = []
    for k, item in enumerate(inputs):
        raw = read_raw(item)
        sources.append(raw.source)
        try:
            j = find_column(raw, time_column, "--time-column")
        except BrainPainterError as exc:
            if "columns of that name" in str(exc):
                raise
            others.extend(h for h in raw.header if h and h not in regions and h not in others)
            continue
        shape = table.shapes[k] if k < len(table.shapes) else detect_shape(raw, table.atlas)
        if shape.kind == "transposed":
            raise BrainPainterError(
                f"--time-column {time_column!r}: {raw.source} is transposed (images as columns); give the "
                "times in a wide table (one row per image) or a long table with an image column."
            )
        times: dict[str, float] = {}
        for i, row in enumerate(raw.rows):
            if shape.image_index is None:
                image = str(i + 1) if shape.kind == "wide" else table.images[0]
            else:
                cell = row[shape.image_index]
                if shape.kind == "wide" and isinstance(cell, float) and cell.is_integer():
                    cell = int(cell)
                image = "" if cell is None else str(cell).strip()
            cell = row[j] if j < len(row) else None
            t = to_number(cell, raw.decimal_comma)
            if t is None or not math.isfinite(t):
                what = "empty" if t is not None and math.isnan(t) else f"{str(cell)[:40]!r}"
                raise BrainPainterError(
                    f"--time-column {time_column!r}: {raw.where(i)} of {raw.source} is {what}, not a finite "
                    "number; give every row a numeric time (e.g. years or a stage number)."
                )
            if image in times and times[image] != t:
                raise BrainPainterError(
                    f"--time-column {time_column!r}: image {image!r} has two times ({times[image]:g} and "
                    f"{t:g}); give each image one time."
                )
            times[image] = t
        lacking = [im for im in table.images if im not in times]
        if lacking:
            raise BrainPainterError(
                f"--time-column {time_column!r}: image {lacking[0]!r} has no time in {raw.source}; "
                "give every image a time."
            )
        return raw.header[j], {im: times[im] for im in table.images}
    close = nearest(time_column, others)
    shown = others[:8] + (["..."] if len(others) > 8 else [])
    raise BrainPainterError(
        f"--time-column {time_column!r} is not a column of {', '.join(sources)}; its columns that are not "
        f"regions are {shown}" + (f". Did you mean {close[0]!r}?" if close else
                                  ". Add a numeric column with each row's time.")
    )


def key_frames(table: RegionTable, rows: Sequence[int], times: Mapping[str, float] | None,
               time_column: str | None = None) -> tuple[list[int], list[float]]:
    """Key-frame rows in movie order and their times (positions 0, 1, ... without a time column)."""
    if len(rows) < 2:
        shown = [table.images[i] for i in rows]
        raise BrainPainterError(
            f"a movie needs at least 2 rows (key frames); the input has {len(rows)} ({shown}). Add rows, "
            "or use 'brainpainter figure' or 'render' for one image."
        )
    if times is None:
        return list(rows), [float(i) for i in range(len(rows))]
    order = sorted(rows, key=lambda i: times[table.images[i]])
    ts = [times[table.images[i]] for i in order]
    for x, y, t0, t1 in zip(order, order[1:], ts, ts[1:], strict=False):
        if t0 == t1:
            raise BrainPainterError(
                f"--time-column {time_column!r}: images {table.images[x]!r} and {table.images[y]!r} have the "
                f"same time {t0:g}; key frames need different times."
            )
    return order, ts


# -- orbit -----------------------------------------------------------------------------
def orbit_views(painter: Painter, view: View, azimuths: Sequence[float], aspect: float) -> list[View]:
    """`view` turned to each azimuth, zoomed so the image scale stays that of the widest direction."""
    from brainpainter.rendering.framing import extent

    # the hull points the camera frames (brainpainter.rendering.geometry), so the orbit and each image agree
    points = np.vstack([p.hull for p in painter.scene.geometry.visible(view)])
    extents = [extent(points, az, view.elevation, aspect) for az in azimuths]
    widest = max((e for e in extents if e), default=None)
    out = []
    for az, e in zip(azimuths, extents, strict=True):
        zoom = view.zoom * (e / widest if e and widest else 1.0)
        out.append(replace(view, azimuth=float(az) % 360.0, zoom=zoom))
    return out


# -- frame composition ------------------------------------------------------------------
def _font(size: int) -> Any:
    """DejaVu Sans (shipped with matplotlib) at `size` pixels."""
    from matplotlib import font_manager
    from PIL import ImageFont

    path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans"))
    return ImageFont.truetype(path, max(6, int(size)))


def _over(rgba: np.ndarray, bg: np.ndarray) -> np.ndarray:
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
    """

    def __init__(self, n_views: int, size: tuple[int, int], scale: ColourScale, key_clock: Sequence[float],
                 *, background: ColorLike = "white", label: str | None = None,
                 ticks: Sequence[float] | str | None = None, nan: bool = False, missing: bool = False,
                 title: str | None = None) -> None:
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
        cb_args = {"label": label, "ticks": ticks, "nan": nan, "missing": missing,
                   "fontsize": max(6.0, 16.0 * u)}
        cb_h = max(56, round(110 * u), math.ceil(colorbar_height(scale, cb_w / 100.0, **cb_args) * 100))
        cb_h += cb_h % 2
        caption_h = round(92 * u)
        footer = max(cb_h, caption_h) if side else cb_h + caption_h
        height = self.header + h + footer
        self.size = (width + width % 2, height + height % 2)
        W, H = self.size
        canvas = np.empty((H, W, 3), np.uint8)
        canvas[:] = self.bg
        cb = colorbar_image(scale, (cb_w, cb_h), background=background, **cb_args)
        y0 = self.header + h + (footer - cb_h if side else caption_h)
        x0 = W - cb_w - pad if side else (W - cb_w) // 2
        canvas[y0:y0 + cb_h, x0:x0 + cb_w] = _over(cb, self.bg)
        self.caption_box = (pad, self.header + h, (x0 - pad) if side else (W - pad),
                            self.header + h + caption_h)
        if title:
            from PIL import Image, ImageDraw

            im = Image.fromarray(canvas)
            ImageDraw.Draw(im).text((W / 2, self.header / 2 + round(4 * u)), title, fill=self.fg,
                                    font=self.title_font, anchor="mm")
            canvas = np.asarray(im).copy()
        self.canvas = canvas

    def compose(self, renders: Sequence[np.ndarray], caption: str, clock: float) -> np.ndarray:
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


# -- writers -----------------------------------------------------------------------------
class _Mp4Writer:
    def __init__(self, path: Path, size: tuple[int, int], fps: float) -> None:
        import imageio_ffmpeg

        self.path = path

        self._gen = imageio_ffmpeg.write_frames(
            str(path), size, fps=fps, codec="libx264", pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
            quality=None, macro_block_size=2, ffmpeg_log_level="quiet",  # failures: verified after
            # sRGB frames -> BT.709 YUV, tagged as such so players convert back the same way
            output_params=["-crf", "18", "-preset", "medium", "-vf", "scale=out_color_matrix=bt709",
                           "-x264-params", "colorprim=bt709:transfer=bt709:colormatrix=bt709",
                           "-movflags", "+faststart"],
        )
        self._gen.send(None)

    def write(self, frame: np.ndarray) -> None:
        try:
            self._gen.send(np.ascontiguousarray(frame))
        except (OSError, RuntimeError, StopIteration) as exc:
            raise self._failed(exc) from None

    def close(self) -> None:
        try:
            self._gen.close()
        except (OSError, RuntimeError) as exc:
            raise self._failed(exc) from None

    def _failed(self, exc: BaseException) -> BrainPainterError:
        from brainpainter.io.verify import _broken

        return _broken(self.path, f"the video encoder (ffmpeg) stopped: {type(exc).__name__}")

    def abort(self) -> None:
        self._gen.close()  # ffmpeg finishes the temporary file, which is then deleted


class _GifWriter:
    """GIF written frame by frame: one palette for the whole movie, Floyd-Steinberg dithered.

    A shared palette keeps still parts (colour bar, unchanged regions) identical
    from frame to frame, so dithering does not flicker. The palette comes from
    a mosaic of up to 12 frames spread over the movie (given up front), and each
    frame is quantised and appended to the file as it comes, so memory does
    not grow with the number of frames.
    """

    def __init__(self, path: Path, size: tuple[int, int], fps: float,
                 background: tuple[int, int, int] = (255, 255, 255),
                 samples: Sequence[np.ndarray] = ()) -> None:
        self.path, self.fps, self.background = path, fps, tuple(int(c) for c in background)
        self.size = size
        self.n_frames = 0
        self._palette = self.palette(samples)
        self._fh = path.open("wb")
        colors = bytes(self._palette.getpalette()[: 3 * 256])
        colors += bytes(self.background) * ((768 - len(colors)) // 3)
        self._fh.write(b"GIF89a" + struct.pack("<HHBBB", size[0], size[1], 0xF7, 255, 0) + colors)
        # loop forever (NETSCAPE2.0 application extension)
        self._fh.write(b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", 0) + b"\x00")

    def palette(self, samples: Sequence[np.ndarray]) -> Any:
        """255 colours from a mosaic of the sample frames, plus the exact background colour."""
        from PIL import Image

        colors = np.array([self.background], np.uint8)
        if len(samples):
            mosaic = np.concatenate([f[::2, ::2] for f in samples], axis=0)
            sampled = Image.fromarray(np.ascontiguousarray(mosaic)).quantize(
                colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            colors = np.array(sampled.getpalette()[: 3 * 255], dtype=np.uint8).reshape(-1, 3)[:255]
        colors = np.vstack([colors, np.array([self.background] * (256 - len(colors)), np.uint8)])
        palette = Image.new("P", (1, 1))
        palette.putpalette(colors.ravel().tolist())
        return palette

    def write(self, frame: np.ndarray) -> None:
        from PIL import GifImagePlugin, Image

        im = Image.fromarray(np.ascontiguousarray(frame)).quantize(palette=self._palette,
                                                                 dither=Image.Dither.FLOYDSTEINBERG)
        # pillow's palette look-up is approximate: put the background back exactly (index 255)
        bg = Image.fromarray(((frame == self.background).all(axis=-1) * 255).astype(np.uint8))
        im.paste(255, mask=bg)
        params = {"duration": max(20, round(1000 / self.fps / 10) * 10), "disposal": 1}
        write_frame = getattr(GifImagePlugin, "_write_frame_data", None)
        if write_frame is not None:  # straight into the file
            write_frame(self._fh, im, (0, 0), params)
        else:  # pragma: no cover - older/newer pillow: the public (but leakier) frame encoder
            for part in GifImagePlugin.getdata(im, **params):
                self._fh.write(part)
        self.n_frames += 1

    def abort(self) -> None:
        self._fh.close()

    def close(self) -> None:
        self._fh.write(b";")
        self._fh.close()


# -- the job ------------------------------------------------------------------------------
@dataclass
class MovieResult:
    """What :func:`make_movie` made.

    Attributes
    ----------
    path : Path
    n_frames : int
    frame_size : (int, int)
        Width and height in pixels.
    fps : float
    keys : list of str
        Image names of the key frames, in movie order.
    key_times : list of float
        Their times (positions 0, 1, ... without a time column).
    seconds : float
        Wall time spent making the movie (rendering, composing, encoding).
    """

    path: Path
    n_frames: int
    frame_size: tuple[int, int]
    fps: float
    keys: list[str]
    key_times: list[float]
    seconds: float

    @property
    def duration(self) -> float:
        """Length of the movie in seconds."""
        return self.n_frames / self.fps


def make_movie(
    data: Any,
    atlas: Atlas | str | None = None,
    *,
    out: str | Path,
    views: str | Sequence[str] | None = None,
    rows: Iterable[str | int] | str | None = None,
    frames_per_step: int = 24,
    easing: str = "linear",
    time_column: str | None = None,
    hold: int = 0,
    fps: float = 24.0,
    orbit: float = 0.0,
    label: str | None = None,
    ticks: Sequence[float] | str | None = None,
    title: str | None = None,
    template: Template | str = "fsaverage",
    surface: str = "pial",
    gradient: Sequence[ColorLike] | str | None = None,
    cmap: str | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    center: float | None = None,
    nan_color: ColorLike = DEFAULT_NAN_COLOR,
    missing_color: ColorLike = DEFAULT_MISSING_COLOR,
    hide: Iterable[str] = (),
    background: ColorLike | None = "white",
    width: int = 800,
    height: int = 600,
    quality: str = "default",
    shading: str = "default",
    lighting: str = "studio",
    glass_opacity: float = 0.12,
    renderer: str = "blender",
    image_column: str | None = None,
    value: str | None = None,
    region_column: str | None = None,
    strict: bool = False,
    progress: bool = True,
    atlas_config: str | Path | None = None,
    jobs: int | str = 1,
    client: Any = None,
    scheduler: str | None = None,
) -> MovieResult:
    """Make a movie through the rows of a region-value table.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table`; at least 2 rows.
    atlas : str or Atlas, optional
    out : path
        ``.mp4`` (H.264) or ``.gif``.
    views : str or list of str, optional
        Side by side in each frame; default ``lateral-left, medial-left, subcortical``.
    rows : iterable of str or int, or str, optional
        Image names (or 0-based positions) to use as key frames, in this order
        (sorted by time with `time_column`); default all rows.
    frames_per_step : int
        Frames from one key frame to the next (``(keys - 1) * N + 1`` in all).
        With `time_column`, steps get frames in proportion to their time gaps
        (N per step on average).
    easing : {"linear", "smooth"}
        ``smooth`` (smoothstep) slows down into and out of each key frame.
    time_column : str, optional
        A numeric column giving each row's time (e.g. years); rows are sorted by
        it and the caption shows the time.
    hold : int
        Extra frames showing each key frame still.
    fps : float
        Frames per second (1 to 60; GIF at most 50).
    orbit : float
        Degrees the camera turns about the vertical axis over the whole movie
        (360: one full turn that loops seamlessly); 0: fixed camera.
    label, ticks
        Colour-bar label and ticks, see :func:`brainpainter.media.colorbar.draw_colorbar`.
    title : str, optional
        A line above the views.
    template, surface, gradient, cmap, vmin, vmax, center, nan_color, missing_color, hide,
    background, width, height, quality, shading, lighting, glass_opacity, renderer
        As for :func:`brainpainter.render`; width and height are the size
        of each view (default 800 x 600). A movie has no transparency: the
        background must be a colour.
    image_column, value, region_column, strict
        How the table is read, see :func:`brainpainter.table.region_table.read_table`.
    progress : bool
        Show a progress bar.
    atlas_config : path, optional
        Region-group TOML file defining the atlas, as for :func:`brainpainter.render`.
    jobs, client, scheduler
        Render frames on worker processes or a Dask cluster, as for
        :func:`brainpainter.render`; frames are encoded in order.

    Returns
    -------
    MovieResult
    """
    from tqdm.auto import tqdm

    from brainpainter.io.transaction import FileTransaction
    from brainpainter.media.colorbar import resolve_ticks
    from brainpainter.media.figure import check_out_file, select_rows, swatches_needed
    from brainpainter.rendering.painter import Painter, prepare_run, region_colors
    from brainpainter.rendering.parallel import Item, check_options, make_runner

    start = time.perf_counter()
    path = check_out_file(out, MOVIE_FORMATS)
    check_options(jobs, client, scheduler)
    fmt = path.suffix.lower()
    if background is None:
        raise BrainPainterError("a movie has no transparency; give a background colour (--background) "
                                "instead of --transparent.")
    top_fps = 50.0 if fmt == ".gif" else 60.0
    if not 1.0 <= float(fps) <= top_fps:
        raise BrainPainterError(
            f"fps must be between 1 and {top_fps:g} for {fmt[1:].upper()}; {fps:g} was given.")
    if not math.isfinite(float(orbit)):
        raise BrainPainterError(f"orbit must be a number of degrees; {orbit!r} was given.")
    ease(0.0, easing)
    if hasattr(data, "read") and callable(data.read) and time_column is not None:
        data = data.read()  # read twice below: once for the regions, once for the times
    run = prepare_run(
        data, atlas, views=views, gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center,
        nan_color=nan_color, missing_color=missing_color, background=background, width=width,
        height=height, quality=quality, shading=shading, lighting=lighting, glass_opacity=glass_opacity,
        image_column=image_column, value=value, region_column=region_column,
        strict=strict and time_column is None,  # the time column is no region: checked below
        atlas_config=atlas_config,
    )
    resolve_ticks(run.scale, ticks)
    table = run.table
    chosen = select_rows(table.images, rows)
    times = None
    if time_column is not None:
        time_column, times = read_times(data, table, time_column)
        unmatched = [n for n in table.unmatched if n != time_column]
        if strict and unmatched:
            raise BrainPainterError(
                f"--strict: column {unmatched[0]!r} matches no region of atlas {table.atlas.name!r} "
                f"({len(unmatched)} such name(s)); see 'brainpainter check' for the closest names."
            )
    keys, key_times = key_frames(table, chosen, times, time_column)
    plan = plan_frames(key_times, int(frames_per_step), easing, int(hold), proportional=times is not None)
    n = len(plan)
    if fmt == ".gif" and n > MAX_GIF_FRAMES:
        raise BrainPainterError(f"the GIF would have {n} frames; at most {MAX_GIF_FRAMES} are made (a GIF "
                                "is for slides and web pages). Write an .mp4, or lower --frames-per-step or "
                                "--hold.")
    w, h = run.settings.width, run.settings.height
    if len(run.views) * w * h > MAX_FRAME_PIXELS:
        raise BrainPainterError(f"frames of {len(run.views)} views at {w}x{h} are too large; use fewer views "
                                "or a smaller --size.")

    painter = Painter(table.atlas, template, surface, hide, run.settings, renderer)
    nan, missing = swatches_needed(table, keys, run.views, painter.scene.hidden)
    composer = FrameComposer(len(run.views), (w, h), run.scale, key_times, background=background,
                             label=label, ticks=ticks, nan=nan, missing=missing, title=title)
    azimuths = [float(orbit) * i / n for i in range(n)]
    if orbit:
        per_view = [orbit_views(painter, v, [v.azimuth + a for a in azimuths], w / h) for v in run.views]
    else:
        per_view = [[v] * n for v in run.views]
    key_values = table.values[keys]
    names = [table.images[i] for i in keys]

    def caption(f: FramePlan) -> str:
        if times is not None:
            return f"{time_column}: {format_clock(f.clock, key_times)}"
        return names[f.a] if f.a == f.b else f"{names[f.a]} {ARROW} {names[f.b]}"

    # Frames that repeat the previous frame's renders (held key frames) reuse them.
    states: list[tuple[int, int, float, tuple[View, ...]]] = []
    frame_state: list[int] = []
    for i, f in enumerate(plan):
        key = (f.a, f.b, f.weight, tuple(per_view[k][i] for k in range(len(run.views))))
        if not states or states[-1] != key:
            states.append(key)
        frame_state.append(len(states) - 1)
    runner = make_runner(painter, template, jobs=jobs, client=client, scheduler=scheduler,
                         n_items=len(states))

    def chunks(wanted: Iterable[int]) -> Iterator[list[Item]]:
        for s in wanted:
            a, b, weight, state_views = states[s]
            values = interpolate(key_values[a], key_values[b], weight)
            colors = region_colors(dict(zip(table.regions, values.tolist(), strict=True)), table.atlas,
                                   run.scale)
            label = names[a] if a == b else f"{names[a]} {ARROW} {names[b]} ({weight:.3f})"
            yield [Item(colors, view, label=label) for view in state_views]

    def frames(wanted: Sequence[int]) -> Iterator[tuple[int, np.ndarray]]:
        """``(frame index, frame)`` for the frames `wanted` (increasing), rendered in parallel, in order."""
        wanted_states = list(dict.fromkeys(frame_state[i] for i in wanted))
        todo = iter(wanted)
        i = next(todo, None)
        for k, renders in runner.map(chunks(wanted_states), ordered=True):
            while i is not None and frame_state[i] == wanted_states[k]:
                yield i, composer.compose(renders, caption(plan[i]), plan[i].clock)
                i = next(todo, None)

    # the output folder is locked from before the first frame until the movie is published
    with FileTransaction(path) as tx, runner, \
            tqdm(total=n, unit="frame", desc="movie", disable=not progress) as bar:
        samples: dict[int, np.ndarray] = {}
        if fmt == ".gif":  # the palette comes from up to 12 frames spread over the movie
            picks = np.linspace(0, n - 1, min(n, GIF_PALETTE_FRAMES)).round().astype(int)
            samples = dict(frames(sorted(set(picks.tolist()))))
        writer: _Mp4Writer | _GifWriter = (
            _Mp4Writer(tx.tmp, composer.size, float(fps)) if fmt == ".mp4"
            else _GifWriter(tx.tmp, composer.size, float(fps), tuple(composer.bg.tolist()),
                            list(samples.values())))
        try:
            rest = frames([i for i in range(n) if i not in samples])  # rendered in parallel
            for i in range(n):  # encoded in order
                writer.write(samples.pop(i) if i in samples else next(rest)[1])
                bar.update(1)
        except BaseException:
            writer.abort()
            raise
        writer.close()
        tx.commit(size=composer.size if fmt == ".gif" else None, frames=n)
    return MovieResult(path, n, composer.size, float(fps), names, key_times, time.perf_counter() - start)
