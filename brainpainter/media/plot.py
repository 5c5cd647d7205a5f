"""Draw a render into a matplotlib Axes of your own, with an optional colour bar.

:func:`plot` is for composing panels with the rest of a paper's figure::

    import matplotlib.pyplot as plt
    import brainpainter

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(7, 3))
    ax1.plot(years, volume)
    brainpainter.plot("examples/brainpainter_dk.csv", row="stage-4", view="medial-left", ax=ax2,
                      atlas="dk", label="atrophy (SD)")
    fig.savefig("out/panel.pdf")

The colour bar is :func:`brainpainter.media.colorbar.draw_colorbar`, the same as in
``brainpainter figure``; matplotlib is imported when :func:`plot` runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Unpack

from numpy.typing import NDArray

from brainpainter.color.scale import ColourScale
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.media.plain_text import quiet_glyphs

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.image import AxesImage

    from brainpainter.atlas.model import Atlas
    from brainpainter.maps.sections import Section
    from brainpainter.rendering.options import RenderKwargs
    from brainpainter.rendering.painter import Painter, RenderResult

ORIENTATIONS = ("vertical", "horizontal")


@dataclass
class PlotResult:
    """What :func:`plot` drew.

    Attributes
    ----------
    ax : matplotlib.axes.Axes
        The Axes holding the render.
    artist : matplotlib.image.AxesImage
        The render, as drawn by ``ax.imshow``.
    colorbar_ax : matplotlib.axes.Axes or None
        The colour bar's Axes (an inset of `ax`), None without a colour bar.
    image : ndarray of uint8, shape (h, w, 4)
        The RGBA render as drawn (cropped to the brain when ``crop=True``).
    scale : ColourScale
    """

    ax: Axes
    artist: AxesImage
    colorbar_ax: Axes | None
    image: NDArray[Any]
    scale: ColourScale

    def __repr__(self) -> str:
        """One short line."""
        h, w = self.image.shape[:2]
        return f"<PlotResult: {w}x{h} render, scale {self.scale!r}>"


@quiet_glyphs
def plot(values: Any, view: str = "lateral-left", *, ax: Axes | None = None, row: str | int = 0,
         atlas: Atlas | str | None = None, colorbar: bool = True, label: str | None = None,
         ticks: Sequence[float] | str | None = None, orientation: str = "vertical", crop: bool = True,
         painter: Painter | None = None, convention: str = "neurological",
         **render_options: Unpack[RenderKwargs]) -> PlotResult:
    """Render one row of a table from one view into `ax`, with an optional colour bar beside it.

    A view ``"z=50"`` (``x=``, ``y=``) or ``"glass-z"`` (``glass-x``, ``glass-y``) draws a slice or
    glass-brain panel of the run's volume (``volume=``, else ``volume_surface=``) instead, on its
    colour scale (:mod:`brainpainter.media.volume_panels`). Blobs (``volume_surface=``) and cutaways
    (``clip=``, ``"cutaway-left"``) are drawn as :func:`brainpainter.render` draws them.

    Parameters
    ----------
    values : path, DataFrame, dict, or a list of these
        As for :func:`brainpainter.render`, e.g. ``{"Left-entorhinal": 3}``.
    view : str
        One view name (``"lateral-left"``, ``"medial-left"``, ``"subcortical"``,
        ``"camera:AZ:EL[:ZOOM]"``, ...).
    ax : matplotlib.axes.Axes, optional
        Where to draw; default ``matplotlib.pyplot.gca()``. Its axis lines and
        ticks are turned off, and its aspect ratio set to equal.
    row : str or int
        Image name (or 0-based position) of the row to draw; default the first.
        The colour scale is computed over all rows, as for ``render``.
    atlas : str or Atlas, optional
        Inferred from the region names when not given.
    colorbar : bool
        Draw a colour bar in an inset Axes beside `ax` (right of it when
        `orientation` is ``"vertical"``, under it when ``"horizontal"``), with
        swatches for the NaN and missing colours when those are drawn.
    label : str, optional
        Colour-bar label, e.g. ``"z-score"``.
    ticks : sequence of float or str, optional
        Colour-bar ticks; default the gradient's colours.
    orientation : {"vertical", "horizontal"}
    crop : bool
        Cut the background around the brain, so the brain fills `ax`.
    painter : Painter, optional
        A loaded :class:`~brainpainter.rendering.painter.Painter` to reuse (no new scene).
    convention : {"neurological", "radiological"}
        A slice or glass-brain panel: left on the left (default) or on the right.
    **render_options
        The options of a run, as for :func:`brainpainter.render`
        (:class:`brainpainter.rendering.options.Options`: ``gradient``, ``cmap``,
        ``vmin``, ``vmax``, ``center``, ``template``, ``surface``, ``hide``,
        ``width``, ``height``, ``quality``, ``shading``, ``lighting``, ...).

    Returns
    -------
    PlotResult
    """
    _check_plot_options(orientation, render_options)
    from brainpainter.maps.sections import parse_panel
    from brainpainter.media.drawn import common_crop
    from brainpainter.rendering.run import render

    section = parse_panel(view)
    if section is not None:
        return _plot_panel(values, section, ax, row, atlas, (colorbar, label, ticks, orientation), convention,
                           dict(render_options))
    options: dict[str, Any] = {**render_options, "views": [view]}
    result = render(values, atlas, rows=[row], painter=painter, progress=False, **options)
    (_, view_name), image = next(iter(result.images.items()))
    scale = result.scale
    assert scale is not None
    background = result.manifest["settings"]["background"]
    if crop:
        rows_, cols = common_crop([image], background)
        image = image[rows_, cols]
    if ax is None:
        import matplotlib.pyplot as plt

        ax = plt.gca()
    artist = ax.imshow(image, interpolation="antialiased")
    ax.set_axis_off()
    ax.set_aspect("equal")
    cax = (_colorbar(ax, result, row, view_name, label, ticks, orientation, painter, options.get("template"))
           if colorbar else None)
    return PlotResult(ax, artist, cax, image, scale)


def _colorbar(ax: Axes, result: RenderResult, row: str | int, view_name: str, label: str | None,
              ticks: Sequence[float] | str | None, orientation: str, painter: Painter | None,
              template: Any) -> Axes:
    """The colour bar of a plot in an inset of `ax`, with the swatches of the colours it draws."""
    from brainpainter.media.colorbar import draw_colorbar
    from brainpainter.media.drawn import swatches_needed
    from brainpainter.rendering.layers import without_regions
    from brainpainter.rendering.views import parse_views
    from brainpainter.table.rows import select_rows

    cax = _bar_axes(ax, orientation)
    table, scale = result.table, result.scale
    assert table is not None and scale is not None
    if painter is not None:
        scene = painter.scene
    else:  # the regions the renderer drew (the scene only: its geometry decides, no renderer is started)
        from brainpainter.rendering.painter import load_scene

        settings = result.manifest["settings"]
        _, scene = load_scene(table.atlas, template or "fsaverage", settings["surface"], settings["hidden"])
    alone = without_regions(result.layers)
    nan, missing = ((False, False) if alone else
                    swatches_needed(table, select_rows(table.images, [row]), parse_views([view_name]),
                                    scene.geometry))
    draw_colorbar(cax, scale, label=label, ticks=ticks, orientation=orientation, nan=nan, missing=missing)
    return cax


def _plot_panel(values: Any, section: Section, ax: Axes | None, row: str | int, atlas: Atlas | str | None,
                bar: tuple[bool, str | None, Sequence[float] | str | None, str], convention: str,
                options: dict[str, Any]) -> PlotResult:
    """A slice or glass-brain panel of the run's volume into `ax`; `bar`: colorbar, label, ticks,
    orientation."""
    from brainpainter.media.colorbar import draw_colorbar, text_color
    from brainpainter.media.volume_panels import PanelOptions, label_panel, panel_layer, volume_panels
    from brainpainter.rendering.run import prepare_run
    from brainpainter.table.rows import select_rows

    run: Any = prepare_run(values, atlas, **options)
    i = select_rows(run.table.images, [row])[0]
    opts = PanelOptions(slices=(section.name,) if section.coord is not None else (),
                        projections=None if section.coord is not None else section.axis,
                        convention=convention)
    image = volume_panels(values, run, opts, [i])[(run.table.images[i], section.name)]
    if ax is None:
        import matplotlib.pyplot as plt

        ax = plt.gca()
    artist = ax.imshow(image, interpolation="antialiased")
    ax.set_axis_off()
    ax.set_aspect("equal")
    label_panel(ax, section, convention, text_color(run.settings.background), 8.0)
    colorbar, label, ticks, orientation = bar
    scale = run.scale_of(panel_layer(values, run)[1])
    cax = None
    if colorbar:
        cax = _bar_axes(ax, orientation)
        draw_colorbar(cax, scale, label=label, ticks=ticks, orientation=orientation)
    return PlotResult(ax, artist, cax, image, scale)


def _bar_axes(ax: Axes, orientation: str) -> Axes:
    """The colour bar's inset of `ax`: right of it (vertical) or under it (horizontal)."""
    return ax.inset_axes((1.03, 0.15, 0.045, 0.7) if orientation == "vertical" else (0.15, -0.09, 0.7, 0.05))


def _check_plot_options(orientation: str, render_options: Mapping[str, Any]) -> None:
    """Refuse an unknown orientation and the options of several views or rows (one line)."""
    if orientation not in ORIENTATIONS:
        raise choice_error("orientation", orientation, ORIENTATIONS)
    for reserved in ("views", "out", "rows", "progress"):
        if reserved in render_options:
            raise BrainPainterError(f"plot() draws one view of one row into an Axes; {reserved}= is not "
                                    "one of its options (use view=, row=, or brainpainter.render).")
