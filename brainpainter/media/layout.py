"""Figure layout: renders, headings and colour bars placed at the figure's printed size.

:class:`FigureOptions` is the one definition of the figure options (``--grid``,
``--title``, ``--label``, ``--ticks``, ``--dpi``, ``--fig-width``,
``--font-size``, ``--view-labels``, ``--colorbar-position``), checked when made;
:func:`compose_figure` lays out the renders with them: one colour bar per scaled
layer, horizontal side by side under the images, or upright in a column at their right.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, TypedDict

from numpy.typing import NDArray

from brainpainter.color.rgb import ColorLike
from brainpainter.color.scale import ColourScale
from brainpainter.errors import BrainPainterError, choice_error, within
from brainpainter.media.drawn import common_crop
from brainpainter.media.plain_text import plain, plain_lines

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ONE_COLUMN_IN = 3.5  # inches; journals: 85-90 mm single column, 170-183 mm double
TWO_COLUMN_IN = 7.2
GAP_IN, PAD_IN = 0.04, 0.05  # between images, around the figure
BAR_GAP_IN = 0.3  # between colour bars side by side
RIGHT_GAP_IN = 0.12  # between the images and upright colour bars at their right, and between those bars
#: Where a figure's colour bars go (``--colorbar-position``).
COLORBAR_POSITIONS = ("bottom", "right")


class FigureKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`FigureOptions` (``figure(grid=True, ...)``)."""

    grid: bool
    title: str | None
    label: str | None
    ticks: Sequence[float] | str | None
    dpi: float
    fig_width: float | None
    font_size: float
    view_labels: bool
    colorbar_position: str


def check_figure_text(font_size: float, fig_width: float | None) -> None:
    """Font size in 1..72 points, figure width in 1..40 inches (or None); finite numbers only."""
    if not (within(font_size, 1.0, 72.0) and (fig_width is None or within(fig_width, 1.0, 40.0))):
        raise BrainPainterError(
            f"font size must be 1..72 points and figure width 1..40 inches; font_size={font_size}, "
            f"fig_width={fig_width} were given."
        )


@dataclass(frozen=True)
class FigureOptions:
    """How a figure is laid out; checked when made.

    Attributes
    ----------
    grid : bool
        False: one line of views per image. True: images as columns (headed by
        their names), views as rows, as in BrainPainter's progression figures.
    title : str, optional
        Above everything.
    label : str, optional
        Under the colour bar, e.g. ``"z-score"``.
    ticks : sequence of float or str, optional
        Colour-bar ticks (default: round numbers inside the scale).
    dpi : float
        Resolution of PNG/TIFF output (50 to 1200).
    fig_width : float, optional
        Inches; default 7.2 (two journal columns), or 3.5 for one or two image columns.
    font_size : float
        Points, for column headings and the colour-bar label (ticks one point less,
        title two more).
    view_labels : bool
        Name the views (row labels in a grid, column headings otherwise).
    colorbar_position : {"bottom", "right"}
        The colour bars horizontal under the images, or upright at their right.
    """

    grid: bool = field(default=False, metadata={
        "help": "Rows of the input as columns (e.g. stages) and views as rows, headed by image names."})
    title: str | None = field(default=None, metadata={"help": "A title above the figure."})
    label: str | None = field(default=None, metadata={
        "help": "Colour-bar label, e.g. 'z-score' or 'atrophy (SD from controls)'."})
    ticks: Sequence[float] | str | None = field(default=None, metadata={
        "help": "Colour-bar ticks, e.g. 0,1.5,3 (default: round numbers inside the scale)."})
    dpi: float = field(default=300.0, metadata={"help": "Resolution of PNG/TIFF output."})
    fig_width: float | None = field(default=None, metadata={
        "help": "Figure width in inches (default 7.2, two journal columns; 3.5 for 1-2 image columns)."})
    font_size: float = field(default=8.0, metadata={"help": "Text size in points."})
    view_labels: bool = field(default=False, metadata={
        "help": "Name the views (row labels in a grid, headings otherwise)."})
    colorbar_position: str = field(default="bottom", metadata={
        "choices": COLORBAR_POSITIONS,
        "help": "Where the colour bars go, one per scaled layer, each labelled: horizontal under the images, "
                "or upright at their right."})

    def __post_init__(self) -> None:
        if self.colorbar_position not in COLORBAR_POSITIONS:
            raise choice_error("colorbar_position", self.colorbar_position, COLORBAR_POSITIONS)
        if not within(self.dpi, 50, 1200):
            raise BrainPainterError(f"dpi must be between 50 and 1200; {self.dpi} was given.")
        check_figure_text(self.font_size, self.fig_width)


def pretty_view(name: str) -> str:
    """``lateral-left`` -> ``lateral left``; a slice panel's name as it is (``z=-20``)."""
    return name if "=" in name else name.replace("-", " ")


@dataclass
class FigureLayout:
    """The composed figure and where its parts are (for callers and tests).

    Attributes
    ----------
    figure : matplotlib.figure.Figure
    colorbar_ax : matplotlib.axes.Axes
        The first colour bar's.
    image_axes : dict of (str, str) to Axes
        ``(image name, view name) -> Axes``.
    colorbar_axes : list of Axes
        Every colour bar's, left to right (the first and each later layer's with a scale of its own).
    """

    figure: Figure
    colorbar_ax: Axes | None = None
    image_axes: dict[tuple[str, str], Axes] = field(default_factory=dict)
    colorbar_axes: list[Axes] = field(default_factory=list)


@dataclass
class Grid:
    """Sizes of a figure, inches: the image cells, the margins and the headings.

    Attributes
    ----------
    width, height : float
    left, top, usable : float
        Left margin, top margin (title and headings), width of the image area.
    col_w : list of float, shape (n_cols,)
    row_h : list of float, shape (n_rows,)
    row_heads, col_heads : list of str
    """

    width: float
    height: float
    left: float
    top: float
    usable: float
    col_w: list[float]
    row_h: list[float]
    row_heads: list[str]
    col_heads: list[str]

    def box(self, x: float, y_top: float, w: float, h: float) -> tuple[float, float, float, float]:
        """An axes rectangle in figure fractions from inches (`y_top` measured from the top)."""
        return x / self.width, (self.height - y_top - h) / self.height, w / self.width, h / self.height

    @property
    def col_x(self) -> list[float]:
        """Left edge of each image column, inches."""
        return [self.left + sum(self.col_w[:c]) + GAP_IN * c for c in range(len(self.col_w))]

    @property
    def images_bottom(self) -> float:
        """Where the last row of images ends, inches from the top."""
        return self.top + sum(self.row_h) + GAP_IN * (len(self.row_h) - 1)


def plan_grid(aspect: Mapping[str, float], image_names: Sequence[str], view_names: Sequence[str],
              opts: FigureOptions, colorbar_h: Callable[[float], float], colorbar_w: float = 0.0) -> Grid:
    """Sizes of the figure: `aspect` is each view's height / width after cropping.

    `colorbar_h` gives the colour bars' height (with their labels) for the width of the image
    area, inches; with ``opts.colorbar_position == "right"`` the bars take `colorbar_w` inches
    at the images' right instead.
    """
    grid = opts.grid
    n_cols = len(image_names) if grid else len(view_names)
    width = opts.fig_width or (TWO_COLUMN_IN if n_cols >= 3 else ONE_COLUMN_IN)
    pt = opts.font_size / 72.0
    views = [pretty_view(v) for v in view_names] if opts.view_labels else []
    col_heads = list(image_names) if grid else views
    row_heads = views if grid else (list(image_names) if len(image_names) > 1 else [])
    left = PAD_IN + (1.5 * pt if row_heads else 0.0)
    top = (PAD_IN + (1.6 * (opts.font_size + 2) / 72.0 if opts.title else 0.0)
           + (1.5 * pt if col_heads else 0.0))
    right = opts.colorbar_position == "right"
    usable = width - left - PAD_IN - (colorbar_w if right else 0.0)
    if grid:
        cw = (usable - GAP_IN * (n_cols - 1)) / n_cols
        col_w, row_h = [cw] * n_cols, [cw * aspect[v] for v in view_names]
    else:
        inv = [1.0 / aspect[v] for v in view_names]
        rh = (usable - GAP_IN * (n_cols - 1)) / sum(inv)
        col_w, row_h = [rh * a for a in inv], [rh] * len(image_names)
    if min(col_w) <= 0.05:
        raise BrainPainterError(
            f"the figure is too narrow for {n_cols} image columns at {width:g} in; give a larger "
            "figure width (--fig-width) or fewer rows/views."
        )
    bottom = PAD_IN if right else 0.08 + colorbar_h(usable)
    height = top + sum(row_h) + GAP_IN * (len(row_h) - 1) + bottom
    return Grid(width, height, left, top, usable, col_w, row_h, row_heads, col_heads)


def compose_figure(images: Mapping[tuple[str, str], NDArray[Any]], image_names: Sequence[str],
                   view_names: Sequence[str], scale: ColourScale, opts: FigureOptions | None = None, *,
                   nan: bool = False, missing: bool = False,
                   background: ColorLike | None = "white",
                   more_bars: Sequence[tuple[ColourScale, str]] = (),
                   uncropped: Sequence[str] = ()) -> FigureLayout:
    """Lay out renders, titles and a colour bar in a matplotlib figure.

    Parameters
    ----------
    images : mapping of (image name, view name) to ndarray of uint8, shape (h, w, 4)
        One render per image and view (all of one view the same shape).
    image_names, view_names : sequence of str
        Order of the rows (input) and views.
    scale : ColourScale
    opts : FigureOptions, optional
        Layout, title, colour-bar label and ticks, size and fonts.
    nan, missing : bool
        Show swatches for the NaN and missing colours.
    background : colour or None
        Figure background (and the renders'); None: transparent.
    more_bars : sequence of (ColourScale, str)
        Colour bars of further layers and their labels, beside the first (which has `opts`'
        label, ticks and swatches).
    uncropped : sequence of str
        Views drawn whole (panels of a fixed field of view, such as slices), not cropped to what they show.

    Returns
    -------
    FigureLayout
    """
    from brainpainter.media.colorbar import colorbar_height, new_figure, text_color

    opts = opts or FigureOptions()
    crops = view_crops(images, image_names, view_names, background, uncropped)
    aspect = {v: (crops[v][0].stop - crops[v][0].start) / max(1, crops[v][1].stop - crops[v][1].start)
              for v in view_names}

    bars = [(scale, opts.label, opts.ticks, nan, missing),
            *((s, lb, None, False, False) for s, lb in more_bars)]
    right = opts.colorbar_position == "right"
    if len(bars) > 1 and not right:  # narrower bars side by side: every other round tick where there are many
        bars = [(s, lb, t if t is not None else thinned_ticks(s), n, m) for s, lb, t, n, m in bars]
    widths: list[float] = []
    if right:  # each bar's width; a label longer than the images are tall on two lines
        room = None
        for _ in range(2):
            measured = [colorbar_width(s, dpi=opts.dpi, label=lb, ticks=t, nan=n, missing=m,
                                       fontsize=opts.font_size, room=room) for s, lb, t, n, m in bars]
            widths = [w for w, _ in measured]
            first = plan_grid(aspect, image_names, view_names, opts, lambda _: 0.0,
                              sum(widths) + RIGHT_GAP_IN * len(widths))
            room = first.images_bottom - first.top
        bars = [(s, text, t, n, m) for (s, _, t, n, m), (_, text) in zip(bars, measured, strict=True)]

    def bar_h(usable: float) -> float:
        width = bar_width(usable, len(bars))
        return max(colorbar_height(s, width, dpi=opts.dpi, label=lb, ticks=t, nan=n, missing=m,
                                   fontsize=opts.font_size) for s, lb, t, n, m in bars)

    grid = plan_grid(aspect, image_names, view_names, opts, bar_h, sum(widths) + RIGHT_GAP_IN * len(widths))
    fig = new_figure((grid.width, grid.height), opts.dpi, background)
    layout = FigureLayout(fig)
    color = text_color(background)
    draw_images(layout, grid, images, crops, image_names, view_names, opts.grid)
    draw_headings(fig, grid, opts, color)
    width = bar_width(grid.usable, len(bars))
    x = grid.left + grid.usable
    for k, (s, label, ticks, n, m) in enumerate(bars):
        bar_opts = replace(opts, label=label, ticks=ticks)
        if right:
            x += RIGHT_GAP_IN
            layout.colorbar_axes.append(draw_upright_bar(fig, grid, s, bar_opts, n, m, color, x))
            x += widths[k]
            continue
        slot = (grid.left + k * (width + BAR_GAP_IN), width, 1.0 / len(bars))
        layout.colorbar_axes.append(draw_bar(fig, grid, s, bar_opts, n, m, color, slot))
    layout.colorbar_ax = layout.colorbar_axes[0]
    return layout


def view_crops(images: Mapping[tuple[str, str], NDArray[Any]], image_names: Sequence[str],
               view_names: Sequence[str], background: ColorLike | None, uncropped: Sequence[str] = ()
               ) -> dict[str, tuple[slice, slice]]:
    """Each view's crop (rows, columns): what it shows in any image, or the whole of an `uncropped` view."""
    shapes = {v: images[(image_names[0], v)].shape for v in uncropped}
    return {v: (slice(0, shapes[v][0]), slice(0, shapes[v][1])) if v in shapes
            else common_crop([images[(i, v)] for i in image_names], background) for v in view_names}


def thinned_ticks(scale: ColourScale) -> list[float]:
    """The scale's round ticks, every other one where there are more than 4 (a bar of several)."""
    ticks = [float(t) for t in scale.ticks()]
    return ticks[::2] if len(ticks) > 4 and not scale.categories else ticks


def bar_width(usable: float, n: int) -> float:
    """The width of each of `n` colour bars side by side under images `usable` inches wide."""
    return (usable - BAR_GAP_IN * (n - 1)) / n


def draw_images(layout: FigureLayout, grid: Grid, images: Mapping[tuple[str, str], NDArray[Any]],
                crops: Mapping[str, tuple[slice, slice]], image_names: Sequence[str],
                view_names: Sequence[str], by_column: bool) -> None:
    """One axes per render, cropped; images as columns when `by_column` (a grid figure)."""
    y = grid.top
    col_x = grid.col_x
    for r, rh in enumerate(grid.row_h):
        for c, cw in enumerate(grid.col_w):
            image, view = (image_names[c], view_names[r]) if by_column else (image_names[r], view_names[c])
            ax = layout.figure.add_axes(grid.box(col_x[c], y, cw, rh))
            rows, cols = crops[view]
            ax.imshow(images[(image, view)][rows, cols], interpolation="antialiased")
            ax.set_axis_off()
            layout.image_axes[(image, view)] = ax
        y += rh + GAP_IN


def draw_headings(fig: Figure, grid: Grid, opts: FigureOptions, color: str) -> None:
    """Row labels, column headings and the title."""
    pt, size = opts.font_size / 72.0, opts.font_size
    y = grid.top
    for head, rh in zip(grid.row_heads, grid.row_h, strict=False):
        fig.text((grid.left - 0.4 * pt) / grid.width, 1 - (y + rh / 2) / grid.height, plain(head),
                 rotation=90, ha="right", va="center", fontsize=size, color=color)
        y += rh + GAP_IN
    for x, w, head in zip(grid.col_x, grid.col_w, grid.col_heads, strict=False):
        fig.text((x + w / 2) / grid.width, 1 - (grid.top - 0.35 * pt) / grid.height, plain(head),
                 ha="center", va="bottom", fontsize=size, color=color)
    if opts.title:
        fig.text(0.5, 1 - PAD_IN / grid.height, plain_lines(opts.title), ha="center", va="top",
                 fontsize=size + 2, color=color, fontweight="bold")


def draw_bar(fig: Figure, grid: Grid, scale: ColourScale, opts: FigureOptions, nan: bool, missing: bool,
             color: str, slot: tuple[float, float, float] | None = None) -> Axes:
    """A colour bar, centred right under the images (or in `slot`: its left edge and width, inches, and
    its share of the figure's width); returns its axes."""
    from brainpainter.media.colorbar import draw_colorbar, fit_axes

    x, width, share = slot if slot is not None else (grid.left, grid.usable, 1.0)
    bar_h = 1.1 * opts.font_size / 72.0  # as colorbar_figure draws it
    cb_top = grid.images_bottom + 0.08 + 0.04
    cb_ax = fig.add_axes(grid.box(x, cb_top, width, bar_h))
    draw_colorbar(cb_ax, scale, label=opts.label, ticks=opts.ticks, nan=nan, missing=missing,
                  fontsize=opts.font_size, color=color)
    avail = grid.box(x, cb_top, width, grid.height - cb_top)
    with other_images_hidden(cb_ax):  # its text measured in draws of the figure that resample no render
        fit_axes(cb_ax, avail, grow="x", max_width=share * min(0.55 * grid.width, 3.2) / grid.width)
    # fit_axes centres vertically; keep the bar right under the images instead.
    pos = cb_ax.get_position()
    cb_ax.set_position((pos.x0, 1 - (cb_top + bar_h) / grid.height, pos.width, bar_h / grid.height))
    return cb_ax



@contextmanager
def other_images_hidden(ax: Axes) -> Iterator[None]:
    """The images of the figure's other axes hidden, shown again after: a draw of the figure that
    measures `ax`'s text then resamples no render (the figure's pixels are the same)."""
    from brainpainter.media.colorbar import figure_of

    hidden = [im for other in figure_of(ax).axes if other is not ax for im in other.get_images()
              if im.get_visible()]
    for im in hidden:
        im.set_visible(False)
    try:
        yield
    finally:
        for im in hidden:
            im.set_visible(True)


def colorbar_width(scale: ColourScale, *, dpi: float = 100.0, fontsize: float = 8.0,
                   room: float | None = None, **kwargs: Any) -> tuple[float, str | None]:
    """Width (inches) an upright colour bar needs for itself, its ticks, label and swatches, and its label
    (on two lines where it is longer than `room` inches).

    Parameters as :func:`draw_colorbar` (``label``, ``ticks``, ``nan``, ``missing``).
    """
    from brainpainter.media.colorbar import decorations_bbox, draw_colorbar, new_figure

    fig = new_figure((6.0, 3.0), dpi)
    ax = fig.add_axes((0.05, 0.3, 1.1 * fontsize / 72.0 / 6.0, 0.6))
    draw_colorbar(ax, scale, orientation="vertical", fontsize=fontsize, **kwargs)
    fig.draw_without_rendering()
    label = ax.yaxis.label
    text = label.get_text()
    if room is not None and " " in text and label.get_window_extent().height > room * dpi:
        # at the space nearest the middle: two lines, no word cut ("thicknes" / "s (mm)" was)
        cut = min((i for i, c in enumerate(text) if c == " "), key=lambda i: abs(2 * i - len(text)))
        label.set_text(f"{text[:cut]}\n{text[cut + 1:]}")
        fig.draw_without_rendering()
    box = decorations_bbox(ax)
    return float(box.x1 - ax.get_window_extent().x0) / dpi + 0.02, label.get_text() or None


def draw_upright_bar(fig: Figure, grid: Grid, scale: ColourScale, opts: FigureOptions, nan: bool,
                     missing: bool, color: str, x: float) -> Axes:
    """An upright colour bar at `x` inches from the left, beside the images (its ticks, label and
    swatches to its right and below it); returns its axes."""
    from brainpainter.media.colorbar import draw_colorbar

    thickness = 1.1 * opts.font_size / 72.0  # as a horizontal bar is tall
    tall = grid.images_bottom - grid.top
    height = tall * (0.7 if nan or missing else 0.9)  # swatches below the bar
    cb_ax = fig.add_axes(grid.box(x, grid.top + (tall - height) / (4 if nan or missing else 2), thickness,
                                  height))
    draw_colorbar(cb_ax, scale, label=opts.label, ticks=opts.ticks, orientation="vertical", nan=nan,
                  missing=missing, fontsize=opts.font_size, color=color)
    fit_upright_label(cb_ax, fig.bbox.height * (1 - 2 * PAD_IN / grid.height))
    return cb_ax


def fit_upright_label(ax: Axes, room: float) -> None:
    """An upright bar's label longer than `room` (display pixels, its lines given by
    :func:`colorbar_width`): smaller type, down to 5 pt."""
    from brainpainter.media.colorbar import figure_of

    label = ax.yaxis.label
    if not label.get_text():
        return
    figure_of(ax).draw_without_rendering()
    tall = label.get_window_extent().height
    if tall > room:
        label.set_fontsize(max(5.0, float(label.get_fontsize()) * room / tall))
