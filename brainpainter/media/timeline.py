"""The timeline of a movie: key frames from table rows, their times, and the frames in between.

Rows of the table are key frames, in table order or sorted by a numeric
``time_column``. Between consecutive key frames the values are interpolated
over ``frames_per_step`` frames, linearly or with smooth easing (smoothstep:
slow out of one key frame, slow into the next). A region that is NaN (no
data) in either of two key frames is NaN between them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, ColumnNotFoundError, choice_error, nearest
from brainpainter.table.region_table import RegionTable

EASINGS = ("linear", "smooth")
MAX_FRAMES = 20_000  # frames of one movie (MP4); GIFs: brainpainter.media.encode.MAX_GIF_FRAMES


# -- timing ------------------------------------------------------------------------
def ease(t: NDArray[Any] | float, easing: str = "linear") -> NDArray[Any] | float:
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
    from brainpainter.table.names import NameResolver
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
        except ColumnNotFoundError:
            others.extend(h for h in raw.header if h and h not in regions and h not in others)
            continue
        shape = (table.shapes[k] if k < len(table.shapes)
                 else detect_shape(raw, NameResolver.for_atlas(table.atlas)))
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
