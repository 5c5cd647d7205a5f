"""Movies of a progression: key frames from table rows, interpolated in between.

Rows of the table are key frames, in table order or sorted by a numeric
``time_column``. Between consecutive key frames the values are interpolated
over ``frames_per_step`` frames, linearly or with smooth easing (smoothstep:
slow out of one key frame, slow into the next). A region that is NaN (no
data) in either of two key frames is NaN between them; regions without a
column keep the missing colour. One colour scale, computed from all rows, is
fixed for the whole movie.

Each frame shows the views side by side, and under them the stage (or time)
caption, a timeline with the key frames marked, and the colour bar
(:mod:`brainpainter.media.frames`). Frames are re-colourings of one loaded
scene (:class:`~brainpainter.rendering.painter.Painter`). The timeline is
:mod:`brainpainter.media.timeline`, the encoders :mod:`brainpainter.media.encode`.

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
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Unpack

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.color.scale import ColourScale
from brainpainter.errors import BrainPainterError
from brainpainter.media.drawn import swatches_needed
from brainpainter.media.encode import GIF_PALETTE_FRAMES, MAX_GIF_FRAMES, _GifWriter, _Mp4Writer
from brainpainter.media.frames import FrameComposer, orbit_views, sweep_views
from brainpainter.media.outfile import check_out_file
from brainpainter.media.plain_text import quiet_glyphs
from brainpainter.media.timeline import (
    EASINGS,
    MAX_FRAMES,
    FramePlan,
    ease,
    format_clock,
    key_frames,
    plan_frames,
    read_times,
)
from brainpainter.rendering.checked_run import Run
from brainpainter.rendering.clip import parse_sweep
from brainpainter.rendering.layers import colorbar_layers, first_bar_label, without_regions
from brainpainter.rendering.options import Options, RenderKwargs, take
from brainpainter.rendering.parallel import Item, Runner
from brainpainter.rendering.run import make_runner, prepare_run
from brainpainter.rendering.views import View
from brainpainter.table.rows import select_rows

__all__ = ["MAX_FRAMES", "MAX_GIF_FRAMES", "MovieOptions", "MovieResult", "_GifWriter", "_Mp4Writer", "ease",
           "format_clock", "make_movie", "plan_frames"]

MOVIE_FORMATS = (".mp4", ".gif")
MAX_FRAME_PIXELS = 8192 * 8192
ARROW = "\u2192"


@dataclass(frozen=True)
class MovieOptions:
    """How a movie runs through the key frames, and what its frames show; checked when made.

    Attributes
    ----------
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
    clip_sweep : str, optional
        A cut plane sweeping through the brain over the movie (``"x"``: ``x<v`` from left to right; ``"z>"``:
        from the top down), removing the cortex and glass on its side (:mod:`brainpainter.rendering.clip`).
    title : str, optional
        A line above the views.
    label, ticks
        Colour-bar label and ticks, see :func:`brainpainter.media.colorbar.draw_colorbar`.
    """

    frames_per_step: int = field(default=24, metadata={
        "help": "Frames from one key frame (row) to the next."})
    easing: str = field(default="linear", metadata={
        "choices": EASINGS, "help": "smooth: slow into and out of each key frame."})
    time_column: str | None = field(default=None, metadata={
        "help": "Numeric column with each row's time (e.g. years): rows are sorted by it, steps get "
                "frames in proportion to their gaps, and the caption shows the time."})
    hold: int = field(default=0, metadata={"help": "Extra frames showing each key frame still."})
    fps: float = field(default=24.0, metadata={"help": "Frames per second."})
    orbit: float = field(default=0.0, metadata={
        "help": "Degrees the camera turns around the brain over the movie (360: one full turn)."})
    clip_sweep: str | None = field(default=None, metadata={
        "help": "A cut plane sweeping through the brain over the movie: x (x<v from left to right), x>, y<, "
                "y>, z<, z> (z>: from the top down); what lies inside shows as it passes."})
    title: str | None = field(default=None, metadata={"help": "A title above the views."})
    label: str | None = field(default=None, metadata={"help": "Colour-bar label, e.g. 'z-score'."})
    ticks: Sequence[float] | str | None = field(default=None, metadata={
        "help": "Colour-bar ticks, e.g. 0,1.5,3."})

    def __post_init__(self) -> None:
        if not math.isfinite(float(self.orbit)):
            raise BrainPainterError(f"orbit must be a number of degrees; {self.orbit!r} was given.")
        if self.clip_sweep is not None:
            parse_sweep(self.clip_sweep)
        ease(0.0, self.easing)

    def check_format(self, fmt: str) -> None:
        """The frame rate a format allows (``.gif``: at most 50 fps, ``.mp4``: 60)."""
        top_fps = 50.0 if fmt == ".gif" else 60.0
        if not 1.0 <= float(self.fps) <= top_fps:
            raise BrainPainterError(
                f"fps must be between 1 and {top_fps:g} for {fmt[1:].upper()}; {self.fps:g} was given.")


class MakeMovieKwargs(RenderKwargs, total=False):
    """The keywords of :func:`make_movie`: :class:`MovieOptions` and the run's options."""

    frames_per_step: int
    easing: str
    time_column: str | None
    hold: int
    fps: float
    orbit: float
    clip_sweep: str | None
    title: str | None
    label: str | None
    ticks: Sequence[float] | str | None


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
    scale : ColourScale, optional
        The colour scale of every frame.
    input : dict
        How the input was read (a render manifest's ``input``: unmatched names, notes).
    """

    path: Path
    n_frames: int
    frame_size: tuple[int, int]
    fps: float
    keys: list[str]
    key_times: list[float]
    seconds: float
    scale: ColourScale | None = None
    input: dict[str, Any] = field(default_factory=dict)

    def __repr__(self) -> str:
        """One short line."""
        w, h = self.frame_size
        return (f"<MovieResult: {self.path}, {self.n_frames} frames of {w}x{h} at {self.fps:g} fps, "
                f"{len(self.keys)} key frame(s)>")

    @property
    def duration(self) -> float:
        """Length of the movie in seconds."""
        return self.n_frames / self.fps


@quiet_glyphs
def make_movie(data: Any, atlas: Atlas | str | None = None, *, out: str | Path,
               rows: Iterable[str | int] | str | None = None, progress: bool = True,
               on_progress: Callable[[int, int], None] | None = None,
               **options: Unpack[MakeMovieKwargs]) -> MovieResult:
    """Make a movie through the rows of a region-value table.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table`; at least 2 rows.
    atlas : str or Atlas, optional
    out : path
        ``.mp4`` (H.264) or ``.gif``.
    rows : iterable of str or int, or str, optional
        Image names (or 0-based positions) to use as key frames, in this order
        (sorted by time with `time_column`); default all rows.
    progress : bool
        Show a progress bar.
    on_progress : callable, optional
        Called as ``on_progress(frames_done, n_frames)`` after each frame is encoded; an exception
        it raises stops the movie (nothing is written), e.g. to cancel it.
    **options
        The movie's own: :class:`MovieOptions` (``frames_per_step``, ``easing``,
        ``time_column``, ``hold``, ``fps``, ``orbit``, ``title``, ``label``,
        ``ticks``); and every option of a run, as for :func:`brainpainter.render`
        (:class:`brainpainter.rendering.options.Options`). Width and height are the
        size of each view (default 800 x 600). A movie has no transparency: the
        background must be a colour. Frames render on worker processes or a Dask
        cluster with `jobs`, `client`, `scheduler`; they are encoded in order.

    Returns
    -------
    MovieResult
    """
    from brainpainter.media.colorbar import resolve_ticks

    start = time.perf_counter()
    kwargs: dict[str, Any] = dict(options)
    movie = MovieOptions(**take(kwargs, MovieOptions))
    path = check_out_file(out, MOVIE_FORMATS)
    checked = Options.of(kwargs, "make_movie", width=800, height=600)
    if checked.settings.background is None:
        raise BrainPainterError("a movie has no transparency; give a background colour (--background) "
                                "instead of --transparent.")
    movie.check_format(path.suffix.lower())
    if hasattr(data, "read") and callable(data.read) and movie.time_column is not None:
        data = data.read()  # read twice below: once for the regions, once for the times
    strict = checked.table.strict
    # the time column is no region: checked in movie_keys
    run = prepare_run(data, atlas, options=replace(checked, table=replace(
        checked.table, strict=strict and movie.time_column is None)))
    resolve_ticks(run.scale, movie.ticks)
    keys = MovieKeys.of(data, run, select_rows(run.table.images, rows), movie, strict)
    plan = plan_frames(keys.times, int(movie.frames_per_step), movie.easing, int(movie.hold),
                       proportional=keys.time_name is not None)
    check_frames(len(plan), path.suffix.lower(), run)
    frames = MovieFrames.of(run, keys, plan, movie)
    runner = make_runner(frames.painter, run.options.scene.template, checked.runner,
                         n_items=len(frames.states))
    size = encode(path, frames, runner, float(movie.fps), progress, on_progress)
    return MovieResult(path, len(plan), size, float(movie.fps), keys.names, keys.times,
                       time.perf_counter() - start, run.scale, run.table.summary())


def check_frames(n: int, fmt: str, run: Run) -> None:
    """Refuse a GIF of too many frames, and frames too large to compose."""
    if fmt == ".gif" and n > MAX_GIF_FRAMES:
        raise BrainPainterError(f"the GIF would have {n} frames; at most {MAX_GIF_FRAMES} are made (a GIF "
                                "is for slides and web pages). Write an .mp4, or lower --frames-per-step or "
                                "--hold.")
    w, h = run.settings.width, run.settings.height
    if len(run.views) * w * h > MAX_FRAME_PIXELS:
        raise BrainPainterError(f"frames of {len(run.views)} views at {w}x{h} are too large; use fewer views "
                                "or a smaller --size.")


@dataclass
class MovieKeys:
    """The key frames of a movie, in movie order.

    Attributes
    ----------
    rows : list of int
        Their rows in the table.
    names : list of str
        Their image names.
    times : list of float
        Their times (positions 0, 1, ... without a time column).
    time_name : str or None
        The time column as spelled in the input.
    """

    rows: list[int]
    names: list[str]
    times: list[float]
    time_name: str | None

    @classmethod
    def of(cls, data: Any, run: Run, chosen: Sequence[int], movie: MovieOptions, strict: bool) -> MovieKeys:
        """The key frames of the chosen rows, sorted by the time column when there is one."""
        table, time_name, times = run.table, None, None
        if movie.time_column is not None:
            time_name, times = read_times(data, table, movie.time_column)
            unmatched = [n for n in table.unmatched if n != time_name]
            if strict and unmatched:
                raise BrainPainterError(
                    f"--strict: column {unmatched[0]!r} matches no region of atlas {table.atlas.name!r} "
                    f"({len(unmatched)} such name(s)); see 'brainpainter check' for the closest names."
                )
        if len(chosen) == 1 and (movie.orbit or movie.clip_sweep) and times is None:  # one image turning, cut
            rows, key_times = [chosen[0], chosen[0]], [0.0, 1.0]
        else:
            rows, key_times = key_frames(table, chosen, times, time_name)
        return cls(rows, [table.images[i] for i in rows], key_times, time_name)

    def caption(self, f: FramePlan) -> str:
        """The caption of a frame: the time, or the key frames it lies between."""
        if self.time_name is not None:
            return f"{self.time_name}: {format_clock(f.clock, self.times)}"
        names = self.names
        return names[f.a] if f.a == f.b or names[f.a] == names[f.b] else f"{names[f.a]} {ARROW} {names[f.b]}"


@dataclass
class MovieFrames:
    """What each frame paints and how it is composed.

    Frames that repeat the previous frame's renders (held key frames) share a
    state and reuse its renders.

    Attributes
    ----------
    states : list of (int, int, float, tuple of View)
        Key frames a and b, the weight of b, and the views of each distinct render set.
    frame_state : list of int
        The state of each frame.
    """

    run: Run
    keys: MovieKeys
    plan: list[FramePlan]
    composer: FrameComposer
    painter: Any
    states: list[tuple[int, int, float, tuple[View, ...]]]
    frame_state: list[int]

    @classmethod
    def of(cls, run: Run, keys: MovieKeys, plan: list[FramePlan], movie: MovieOptions) -> MovieFrames:
        painter = run.painter()
        nan, missing = ((False, False) if without_regions(run.layers)
                        else swatches_needed(run.table, keys.rows, run.views, painter.scene.geometry))
        w, h = run.settings.width, run.settings.height
        assert run.settings.background is not None
        more = [(layer.scale, layer.label) for layer in colorbar_layers(run.layers)[1:]]
        label = first_bar_label(run.layers, movie.label, run.options.layers.label(run.layers[0].kind))
        composer = FrameComposer(len(run.views), (w, h), run.scale, keys.times,
                                 background=run.settings.background, label=label, ticks=movie.ticks,
                                 nan=nan, missing=missing, title=movie.title, more_bars=more)
        n = len(plan)
        azimuths = [float(movie.orbit) * i / n for i in range(n)]
        if movie.orbit:
            per_view = [orbit_views(painter, v, [v.azimuth + a for a in azimuths], w / h) for v in run.views]
        else:
            per_view = [[v] * n for v in run.views]
        if movie.clip_sweep:
            per_view = [sweep_views(painter, views, movie.clip_sweep) for views in per_view]
        states: list[tuple[int, int, float, tuple[View, ...]]] = []
        frame_state: list[int] = []
        for i, f in enumerate(plan):
            key = (f.a, f.b, f.weight, tuple(views[i] for views in per_view))
            if not states or states[-1] != key:
                states.append(key)
            frame_state.append(len(states) - 1)
        return cls(run, keys, plan, composer, painter, states, frame_state)

    def chunks(self, wanted: Iterable[int]) -> Iterator[list[Item]]:
        """The renders of each wanted state, one chunk per state."""
        names, rows = self.keys.names, self.keys.rows
        for s in wanted:
            a, b, weight, state_views = self.states[s]
            colors = self.run.blend(rows[a], rows[b], weight)  # every layer's values between key frames
            label = names[a] if a == b else f"{names[a]} {ARROW} {names[b]} ({weight:.3f})"
            yield [Item(colors, view, label=label) for view in state_views]

    def frames(self, runner: Runner, wanted: Sequence[int]) -> Iterator[tuple[int, NDArray[Any]]]:
        """``(frame index, frame)`` for the frames `wanted` (increasing), rendered in parallel, in order."""
        wanted_states = list(dict.fromkeys(self.frame_state[i] for i in wanted))
        todo = iter(wanted)
        i = next(todo, None)
        for k, renders in runner.map(self.chunks(wanted_states), ordered=True):
            while i is not None and self.frame_state[i] == wanted_states[k]:
                f = self.plan[i]
                yield i, self.composer.compose(renders, self.keys.caption(f), f.clock)
                i = next(todo, None)


def encode(path: Path, frames: MovieFrames, runner: Runner, fps: float, progress: bool,
           on_progress: Callable[[int, int], None] | None = None) -> tuple[int, int]:
    """Render, compose and encode every frame into `path`, published atomically; returns the frame size.

    `on_progress(done, n)` is called after each frame is encoded (see :func:`make_movie`).
    """
    from tqdm.auto import tqdm

    from brainpainter.io.transaction import FileTransaction

    n, composer, gif = len(frames.plan), frames.composer, path.suffix.lower() == ".gif"
    # the output folder is locked from before the first frame until the movie is published
    with FileTransaction(path) as tx, runner, \
            tqdm(total=n, unit="frame", desc="movie", disable=progress is not True) as bar:
        samples: dict[int, NDArray[Any]] = {}
        if gif:  # the palette comes from up to 12 frames spread over the movie
            picks = np.linspace(0, n - 1, min(n, GIF_PALETTE_FRAMES)).round().astype(int)
            samples = dict(frames.frames(runner, sorted(set(picks.tolist()))))
        writer: _Mp4Writer | _GifWriter = (
            _GifWriter(tx.tmp, composer.size, fps, tuple(composer.bg.tolist()), list(samples.values()))
            if gif else _Mp4Writer(tx.tmp, composer.size, fps))
        try:
            rest = frames.frames(runner, [i for i in range(n) if i not in samples])  # rendered in parallel
            for i in range(n):  # encoded in order
                writer.write(samples.pop(i) if i in samples else next(rest)[1])
                bar.update(1)
                if on_progress is not None:
                    on_progress(i + 1, n)
        except BaseException:
            writer.abort()
            raise
        writer.close()
        tx.commit(size=composer.size if gif else None, frames=n)
    return composer.size
