"""A connectome's node-size legend: circles over the nodes' colour bar, sized as the spheres are drawn.

The smallest, middle and largest node value are drawn as circles whose diameters keep the ratio of
the spheres' radii (:func:`brainpainter.rendering.connectome_parts.node_radii`): over a bar of values
at those values' places; over a categorical key (the nodes coloured by network) side by side, each
with its value written beside it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.connectome_parts import NODE_RADIUS, node_radii

if TYPE_CHECKING:
    from collections.abc import Sequence

    from matplotlib.axes import Axes

    from brainpainter.color.scale import ColourScale
    from brainpainter.rendering.checked_run import Run

#: Diameter of the largest circle, points.
LARGEST_PT = 8.0
#: Height of the circles' centres over the bar's top (a horizontal bar) or left of it (vertical), points.
GAP_PT = 4.5


def draw_node_sizes(ax: Axes, scale: ColourScale, values: NDArray[Any], color: Any, fontsize: float,
                    horizontal: bool = True) -> bool:
    """Circles for the smallest, middle and largest of `values` (N,) over the nodes' bar `ax`.

    Returns
    -------
    bool
        False when there is nothing to show (no finite value, or all equal: every sphere one size).
    """
    from matplotlib.transforms import offset_copy

    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if not finite.size or finite.min() == finite.max():
        return False
    shown = np.array([finite.min(), (finite.min() + finite.max()) / 2, finite.max()])
    diameters = node_radii(shown, 3) / NODE_RADIUS[1] * LARGEST_PT
    categorical = bool(scale.categories)
    where = (np.array([0.2, 0.5, 0.8]) if categorical
             else scale.position(shown) / max(scale.n_colors - 1, 1))
    shift = {"y": GAP_PT} if horizontal else {"x": -GAP_PT}
    transform = offset_copy(ax.transAxes, fig=ax.figure, units="points", **shift)  # type: ignore[arg-type]
    xs, ys = (where, np.ones(3)) if horizontal else (np.zeros(3), where)
    ax.scatter(xs, ys, s=diameters**2, transform=transform, clip_on=False, facecolor="none",
               edgecolor=color, linewidth=0.8)
    if categorical:
        for x, y, d, v in zip(xs, ys, diameters, shown, strict=True):
            ax.annotate(f"{v:.3g}", (x, y), xycoords=transform, xytext=(d / 2 + 2, 0),
                        textcoords="offset points", va="center", fontsize=fontsize - 2, color=color)
    return True


def node_size_legend(run: Run, bar_axes: Sequence[Axes], color: Any, fontsize: float) -> bool:
    """The node-size legend over the nodes' bar of a figure of `run` (`bar_axes`: one per colour bar),
    where its connectome's nodes have values; False where there is none."""
    from brainpainter.rendering.layers import colorbar_layers

    connectome = run.connectome
    kinds = [layer.kind for layer in colorbar_layers(run.layers)]
    if connectome is None or connectome.node_values is None or "nodes" not in kinds:
        return False
    return draw_node_sizes(bar_axes[kinds.index("nodes")], run.scale_of("nodes"), connectome.node_values,
                           color, fontsize)
