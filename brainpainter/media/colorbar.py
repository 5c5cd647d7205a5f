"""Colour bars for a :class:`~brainpainter.color.scale.ColourScale`, drawn with matplotlib.

The bar shows exactly the colours the renders use: it samples the scale itself (``scale(values)``), so
a BrainPainter gradient appears with its control colours at its ticks and a matplotlib colour map as a
smooth ramp; tick labels that would overprint are thinned (:mod:`brainpainter.media.tick_labels`). Ticks
default to round numbers (:meth:`ColourScale.ticks`: a gradient's control points where round); NaN and
missing swatches are added when asked; a label map's scale draws a key of its categories
(:mod:`brainpainter.media.category_key`). Labels are the user's text, never mathtext
(:mod:`brainpainter.media.plain_text`). :func:`draw_colorbar` draws into an Axes (figures);
:func:`colorbar_image` returns an RGBA array of an exact pixel size (movie frames).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.scale import ColourScale, between, fraction
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.media.category_key import draw_category_key
from brainpainter.media.plain_text import plain, plain_lines
from brainpainter.media.tick_labels import thin_tick_labels

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.axis import Axis
    from matplotlib.figure import Figure

#: Samples along the bar; enough for a smooth ramp at print resolution.
N_SAMPLES = 512
NAN_LABEL = "no data"
MISSING_LABEL = "not measured"
ORIENTATIONS = ("horizontal", "vertical")


def format_tick(value: float) -> str:
    """A short tick label: ``0``, ``1.5``, ``-2``, ``0.001``, ``1.2e+04`` (no ``-0``)."""
    if value == 0:  # also -0.0
        return "0"
    return f"{value:.3g}"


def resolve_ticks(scale: ColourScale, ticks: Sequence[float] | str | None) -> NDArray[Any]:
    """Tick values: the scale's round ticks by default, or `ticks` checked against the scale.

    Parameters
    ----------
    scale : ColourScale
    ticks : sequence of float, or str like ``"0,1.5,3"``, optional

    Returns
    -------
    ndarray of float, shape (n_ticks,), sorted.

    Raises
    ------
    BrainPainterError
        A tick that is not a number or lies outside ``[vmin, vmax]``.
    """
    if ticks is None:
        return np.asarray(scale.ticks(), dtype=float)
    items = ticks.replace(";", ",").split(",") if isinstance(ticks, str) else list(ticks)
    values = []
    for item in items:
        if isinstance(item, str) and not item.strip():
            continue
        try:
            v = float(item)
        except (TypeError, ValueError):
            raise BrainPainterError(
                f"ticks must be numbers, e.g. --ticks 0,1.5,3; {item!r} was given."
            ) from None
        if not np.isfinite(v):
            raise BrainPainterError(f"ticks must be finite numbers; {item!r} was given.")
        values.append(v)
    if not values:
        raise BrainPainterError(f"no tick value in {ticks!r}; give numbers, e.g. --ticks 0,1.5,3")
    where = fraction(np.asarray(values, dtype=float), scale.vmin, scale.vmax)
    outside = [v for v, t in zip(values, where, strict=True) if not -1e-9 <= t <= 1 + 1e-9]
    if outside:
        raise BrainPainterError(
            f"tick {outside[0]:g} lies outside the colour scale {scale.vmin:g}..{scale.vmax:g}; "
            "give ticks inside it, or widen the scale with --vmin/--vmax."
        )
    unique: NDArray[Any] = np.unique(np.asarray(values, dtype=float))
    return unique


def bar_colors(scale: ColourScale, n: int = N_SAMPLES) -> tuple[NDArray[Any], NDArray[Any]]:
    """Values from vmin to vmax and their colours.

    Returns
    -------
    values : ndarray of float, shape (n,)
    colors : ndarray of float, shape (n, 3), sRGB 0-1
    """
    values = between(scale.vmin, scale.vmax, np.linspace(0.0, 1.0, n))  # no overflow at +-1e308
    return values, np.clip(scale(values), 0.0, 1.0)


#: Colour of the band of a map's colour bar below the threshold (the underlay's grey).
THRESHOLD_GREY = (0.72, 0.72, 0.72)


def _threshold_band(ax: Axes, scale: ColourScale, horizontal: bool) -> None:
    """Grey out ``|v| < scale.threshold`` on the bar and mark its edges with thin lines."""
    t = scale.threshold
    if t is None or t <= 0:
        return
    lo, hi = max(-t, scale.vmin), min(t, scale.vmax)
    if lo >= hi:
        return
    span = ax.axvspan if horizontal else ax.axhspan
    line = ax.axvline if horizontal else ax.axhline
    # the bar is drawn in fractions of the scale (0..1): place the band there too
    flo, fhi = (float(f) for f in fraction(np.array([lo, hi]), scale.vmin, scale.vmax))
    span(flo, fhi, color=THRESHOLD_GREY, zorder=2)
    for edge in (-t, t):
        if scale.vmin < edge < scale.vmax:
            at = float(fraction(np.array([edge]), scale.vmin, scale.vmax)[0])
            line(at, color="black", linewidth=0.6, zorder=3)


def draw_colorbar(
    ax: Axes,
    scale: ColourScale,
    *,
    label: str | None = None,
    ticks: Sequence[float] | str | None = None,
    orientation: str = "horizontal",
    nan: bool = False,
    missing: bool = False,
    nan_label: str = NAN_LABEL,
    missing_label: str = MISSING_LABEL,
    fontsize: float = 8.0,
    color: Any = "black",
) -> Axes:
    """Draw a colour bar of `scale` filling the Axes `ax`.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The bar fills it; tick labels and the label go outside it.
    scale : ColourScale
    label : str, optional
        Quantity and unit, e.g. ``"atrophy (SD from controls)"``.
    ticks : sequence of float or str, optional
        Default: round numbers inside the scale (a gradient's control points where round).
    orientation : {"horizontal", "vertical"}
    nan, missing : bool
        Add a swatch for the NaN colour (empty cells) / the missing colour
        (regions without a value), beside the bar (horizontal) or below it.
    nan_label, missing_label : str
        Their captions.
    fontsize : float
        Points; tick labels use ``fontsize - 1``.
    color : colour
        Text and outline colour (white on a dark background).

    Returns
    -------
    matplotlib.axes.Axes
        `ax`.
    """
    if orientation not in ORIENTATIONS:
        raise choice_error("orientation", orientation, ORIENTATIONS)
    if scale.categories:
        return draw_category_key(ax, scale, orientation == "horizontal", fontsize, color, label)
    tick_values = resolve_ticks(scale, ticks)
    # The bar is drawn in fractions of the scale (0..1), so any finite range (1e-320..1e-310,
    # -1e308..1e308) draws without overflow; ticks are placed at their fractions, one per label.
    where = np.clip(fraction(tick_values, scale.vmin, scale.vmax), 0.0, 1.0)
    labels = [format_tick(t) for t in tick_values]
    keep = [i for i in range(len(labels)) if i == 0 or labels[i] != labels[i - 1]]
    where, labels = where[keep], [labels[i] for i in keep]
    _, colors = bar_colors(scale)
    horizontal = orientation == "horizontal"
    image = colors[None, :, :] if horizontal else colors[::-1, None, :]
    ax.imshow(image, extent=(0.0, 1.0, 0.0, 1.0), aspect="auto", interpolation="nearest", origin="upper")
    _threshold_band(ax, scale, horizontal)
    if horizontal:
        ax.set_xlim(0.0, 1.0)
        ax.set_yticks([])
        ax.set_xticks(where, labels)
        axis: Axis = ax.xaxis
    else:
        ax.set_ylim(0.0, 1.0)
        ax.set_xticks([])
        ax.yaxis.tick_right()
        ax.set_yticks(where, labels)
        axis = ax.yaxis
    ax.tick_params(labelsize=fontsize - 1, length=2.5, width=0.6, pad=1.5, colors=color)
    for spine in ax.spines.values():
        spine.set_linewidth(0.6)
        spine.set_edgecolor(color)
    if label:
        axis.set_label_text(plain_lines(label), fontsize=fontsize, color=color)  # the user's text as text
        if not horizontal:
            ax.yaxis.set_label_position("right")
    _swatches(ax, scale, nan, missing, nan_label, missing_label, fontsize, color, horizontal)
    return ax


def _swatches(ax: Axes, scale: ColourScale, nan: bool, missing: bool, nan_label: str, missing_label: str,
              fontsize: float, color: Any, horizontal: bool) -> None:
    """Swatches of the NaN and missing colours beside a horizontal bar, or below a vertical one."""
    from matplotlib.patches import Patch

    handles = []
    if nan:
        handles.append(Patch(facecolor=scale.nan_color, edgecolor=color, linewidth=0.6,
                             label=plain(nan_label)))
    if missing:
        handles.append(Patch(facecolor=scale.missing_color, edgecolor=color, linewidth=0.6,
                             label=plain(missing_label)))
    if handles:
        loc, anchor, ncol = (("center left", (1.0, 0.5), len(handles)) if horizontal
                             else ("upper center", (0.5, -0.02), 1))
        legend = ax.legend(  # type: ignore[call-overload]
            handles=handles, frameon=False, fontsize=fontsize - 1, handlelength=1.0, handleheight=1.0,
            handletextpad=0.4, columnspacing=0.9, borderaxespad=0.6, labelcolor=color, loc=loc,
            bbox_to_anchor=anchor, ncol=ncol)
        legend.set_in_layout(False)


def colorbar_figure(
    scale: ColourScale,
    width: float,
    height: float,
    *,
    dpi: float = 100.0,
    background: Any = "white",
    label: str | None = None,
    ticks: Sequence[float] | str | None = None,
    nan: bool = False,
    missing: bool = False,
    fontsize: float | None = None,
    nan_label: str = NAN_LABEL,
    missing_label: str = MISSING_LABEL,
) -> Figure:
    """A figure holding only a horizontal colour bar with its ticks, label and swatches.

    Parameters
    ----------
    scale : ColourScale
    width, height : float
        Figure size in inches (``width * dpi`` pixels wide).
    dpi : float
    background : colour or None
        None: transparent.
    fontsize : float, optional
        Points (default 8).
    Other parameters as :func:`draw_colorbar`.

    Returns
    -------
    matplotlib.figure.Figure
        Not attached to pyplot (no GUI backend needed).
    """
    fontsize = 8.0 if fontsize is None else fontsize
    fig = new_figure((width, height), dpi, background)
    pad = 0.04
    bar_h = 1.1 * fontsize / 72.0  # about one line of text
    ax = fig.add_axes((0.1, 0.5, 0.5, bar_h / height))
    draw_colorbar(ax, scale, label=label, ticks=ticks, nan=nan, missing=missing, fontsize=fontsize,
                  color=text_color(background), nan_label=nan_label, missing_label=missing_label)
    fit_axes(ax, (pad / width, pad / height, 1 - 2 * pad / width, 1 - 2 * pad / height), grow="x",
             center=True)
    return fig


def decorations_bbox(ax: Axes, *, label: bool = True) -> Any:
    """Bounding box (display pixels) of `ax` with its tick labels, legend and (optionally) axis label.

    With ``label=False`` the axis label, and a legend moved under the bar,
    are left out (they are centred under the bar and may overhang it).
    """
    from matplotlib.transforms import Bbox

    renderer = agg_canvas(figure_of(ax)).get_renderer()
    boxes = [ax.get_window_extent(renderer)]
    for axis in (ax.xaxis, ax.yaxis):
        boxes.extend(t.get_window_extent(renderer) for t in axis.get_ticklabels() if t.get_visible()
                     and t.get_text())
        if label and axis.label.get_text():
            boxes.append(axis.label.get_window_extent(renderer))
    legend = ax.get_legend()
    if legend is not None and (label or not getattr(legend, "_bp_below", False)):
        boxes.append(legend.get_window_extent(renderer))
    return Bbox.union(boxes)


def fit_axes(ax: Axes, box: tuple[float, float, float, float], *, grow: str = "x",
             center: bool = False, max_width: float | None = None) -> None:
    """Move and resize `ax` so that it and its decorations fill `box`.

    Tick labels, the axis label and a legend keep their size; the axes' own
    extent along `grow` (``"x"``, ``"y"`` or ``"xy"``) absorbs the difference,
    and along the other direction the whole is centred (or kept when it fits).
    A horizontal axis label wider than the bar may overhang it: it is kept
    inside `box` instead.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    box : (left, bottom, width, height)
        Figure fractions.
    grow : {"x", "y", "xy"}
    center : bool
        Centre the whole in `box` along the directions that do not grow.
    max_width : float, optional
        Longest the axes may grow along x, as a figure fraction; the whole is
        then centred in `box`.
    """
    fig = figure_of(ax)
    fw, fh = fig.bbox.width, fig.bbox.height
    bl, bb, bw, bh = box[0] * fw, box[1] * fh, box[2] * fw, box[3] * fh
    legend = ax.get_legend()
    if "x" in grow and legend is not None:
        fig.draw_without_rendering()
        if legend.get_window_extent().width > 0.45 * bw:
            _legend_below(ax)
    placed = None
    for _ in range(3):  # tick labels may move with the size; settle in a few passes
        fig.draw_without_rendering()
        across = decorations_bbox(ax, label=False)  # width: the x label may overhang
        outer = decorations_bbox(ax)
        inner = ax.get_window_extent()
        x0, y0, w, h = inner.x0, inner.y0, inner.width, inner.height
        if "x" in grow:
            w = max(1.0, w + bw - across.width)
            x0 = bl + (inner.x0 - across.x0)
            if max_width is not None and w > max_width * fw:
                x0 += (w - max_width * fw) / 2
                w = max_width * fw
        elif center:
            x0 = bl + (bw - across.width) / 2 + (inner.x0 - across.x0)
        if "y" in grow:
            h = max(1.0, h + bh - outer.height)
            y0 = bb + (inner.y0 - outer.y0)
        elif center:
            y0 = bb + (bh - outer.height) / 2 + (inner.y0 - outer.y0)
        position = (x0 / fw, y0 / fh, w / fw, h / fh)
        if position == placed:  # settled: another pass would measure the same figure again
            break
        ax.set_position(position)
        placed = position
    _keep_label_inside(ax, bl, bl + bw)
    thin_tick_labels(ax, agg_canvas(fig).get_renderer())


def _legend_below(ax: Axes) -> None:
    """Move a colour bar's swatch legend from beside the bar to under its label."""
    fig = figure_of(ax)
    renderer = agg_canvas(fig).get_renderer()
    legend = ax.get_legend()
    if legend is None:
        return
    inner = ax.get_window_extent()
    boxes = [inner]
    boxes.extend(t.get_window_extent(renderer) for t in ax.xaxis.get_ticklabels() if t.get_text())
    if ax.xaxis.label.get_text():
        boxes.append(ax.xaxis.label.get_window_extent(renderer))
    bottom = min(b.y0 for b in boxes)
    legend.set_loc("upper center")
    legend.set_bbox_to_anchor((0.5, (bottom - 1.0 - inner.y0) / inner.height), transform=ax.transAxes)
    legend.borderaxespad = 0.0
    legend._bp_below = True  # type: ignore[attr-defined]
    fig.draw_without_rendering()
    if legend.get_window_extent(renderer).width > fig.bbox.width:
        legend.set_ncols(1)  # one swatch per line


def _keep_label_inside(ax: Axes, lo: float, hi: float) -> None:
    label = ax.xaxis.label
    if not label.get_text():
        return
    fig = figure_of(ax)
    fig.draw_without_rendering()
    renderer = agg_canvas(fig).get_renderer()
    box = label.get_window_extent(renderer)
    if box.width > hi - lo:  # wider than the room: smaller type, down to 5 pt
        label.set_fontsize(max(5.0, float(label.get_fontsize()) * (hi - lo) / box.width))
        box = label.get_window_extent(renderer)
    shift = max(0.0, lo - box.x0) - max(0.0, box.x1 - hi)
    if shift:
        inner = ax.get_window_extent()
        x_axes = 0.5 + shift / inner.width
        ax.xaxis.set_label_coords(x_axes, _label_y(ax))


def _label_y(ax: Axes) -> float:
    """Axes-fraction y just below the tick labels (for a moved x label)."""
    fig = figure_of(ax)
    renderer = agg_canvas(fig).get_renderer()
    inner = ax.get_window_extent()
    ticks = [t.get_window_extent(renderer) for t in ax.xaxis.get_ticklabels() if t.get_text()]
    bottom = min((b.y0 for b in ticks), default=inner.y0)
    return float((bottom - 2.0 - inner.y0) / inner.height)


#: :func:`colorbar_height` of each bar measured in this process, by its scale and options.
_HEIGHTS: dict[str, float] = {}


def colorbar_height(scale: ColourScale, width: float, *, dpi: float = 100.0, **kwargs: Any) -> float:
    """Height (inches) a colour bar of `width` inches needs for its ticks, label and swatches.

    Parameters as :func:`colorbar_figure` (``label``, ``ticks``, ``nan``, ``missing``,
    ``fontsize``); includes the same padding. Measured on a figure of its own (~50 ms), once per
    process for the same bar (a layout asks several times, the next figure of the scale the same).
    """
    key = json.dumps([scale.to_dict(), width, dpi, {k: kwargs[k] for k in sorted(kwargs)}], default=repr)
    if key not in _HEIGHTS:
        if len(_HEIGHTS) >= 256:
            _HEIGHTS.clear()
        outer = decorations_bbox(colorbar_figure(scale, width, 3.0, dpi=dpi, **kwargs).axes[0])
        _HEIGHTS[key] = float(outer.height) / dpi + 2 * 0.04 + 0.02
    return _HEIGHTS[key]


def colorbar_image(
    scale: ColourScale,
    size: tuple[int, int],
    *,
    background: Any = "white",
    **kwargs: Any,
) -> NDArray[Any]:
    """A horizontal colour bar as pixels of an exact size (for movie frames).

    Parameters
    ----------
    scale : ColourScale
    size : (int, int)
        Width and height in pixels.
    background : colour or None
        None: transparent.
    **kwargs
        As :func:`colorbar_figure` (``label``, ``ticks``, ``nan``, ``missing``, ``fontsize``).

    Returns
    -------
    ndarray of uint8, shape (height, width, 4)
        RGBA.
    """
    w, h = (int(s) for s in size)
    dpi = 100.0
    fig = colorbar_figure(scale, w / dpi, h / dpi, dpi=dpi, background=background, **kwargs)
    canvas = agg_canvas(fig)
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba()).copy()
    return pixels[:h, :w]


def new_figure(size: tuple[float, float], dpi: float, background: Any = "white") -> Figure:
    """A matplotlib Figure on an Agg canvas (no pyplot, no GUI backend).

    Parameters
    ----------
    size : (float, float)
        Inches.
    background : colour or None
        None: transparent.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=dpi, facecolor="none" if background is None else background)
    agg_canvas(fig)
    return fig


def figure_of(ax: Axes) -> Figure:
    """The (root) figure of `ax`."""
    fig = ax.get_figure(root=True)
    assert fig is not None
    return fig


def agg_canvas(fig: Figure) -> Any:
    """The figure's Agg canvas (attached on first use)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    return fig.canvas


def text_color(background: Any) -> str:
    """Black on light backgrounds (and transparent ones), white on dark ones."""
    if background is None or (isinstance(background, str) and background == "none"):
        return "black"
    from brainpainter.color.rgb import to_rgb

    r, g, b = to_rgb(background)
    return "black" if 0.2126 * r + 0.7152 * g + 0.0722 * b > 0.45 else "white"
