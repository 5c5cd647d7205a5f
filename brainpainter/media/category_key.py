"""A label map's colour-bar key: one block per category in its own colour, named.

:func:`brainpainter.media.colorbar.draw_colorbar` draws it in the bar's place when the
scale carries categories (``ColourScale.categories``, set for label maps such as a
``.annot``): a gradient of category numbers would mean nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.axis import Axis

    from brainpainter.color.scale import ColourScale


#: The gid of a category key's axes.
CATEGORY_KEY = "category-key"


def draw_category_key(ax: Axes, scale: ColourScale, horizontal: bool, fontsize: float, color: Any,
                      label: str | None) -> Axes:
    """A label map's key in the bar's place: one block per category in its colour, named."""
    import numpy as np

    names = [name for name, _ in scale.categories]
    ax.set_gid(CATEGORY_KEY)  # its names are never thinned (:mod:`brainpainter.media.tick_labels`)
    colors = np.array([rgb for _, rgb in scale.categories], dtype=float)
    n = len(names)
    where = (np.arange(n) + 0.5) / n
    image = colors[None, :, :] if horizontal else colors[::-1, None, :]
    ax.imshow(image, extent=(0.0, 1.0, 0.0, 1.0), aspect="auto", interpolation="nearest", origin="upper")
    # names too many or too long to sit side by side stand upright
    upright = horizontal and n * max(len(name) for name in names) > 60
    if horizontal:
        ax.set_xlim(0.0, 1.0)
        ax.set_yticks([])
        ax.set_xticks(where, names, rotation=90 if upright else 0)
        axis: Axis = ax.xaxis
    else:
        ax.set_ylim(0.0, 1.0)
        ax.set_xticks([])
        ax.yaxis.tick_right()
        ax.set_yticks(where[::-1], names)
        axis = ax.yaxis
    for edge in np.arange(1, n) / n:  # a thin line between blocks of similar colour
        (ax.axvline if horizontal else ax.axhline)(edge, color=color, linewidth=0.4)
    ax.tick_params(labelsize=max(fontsize - 1 - (2 if n > 20 else 0), 4), length=2.5, width=0.6, pad=1.5,
                   colors=color)
    for spine in ax.spines.values():
        spine.set_linewidth(0.6)
        spine.set_edgecolor(color)
    if label:
        axis.set_label_text(label, fontsize=fontsize, color=color)
    return ax
