"""A label map's colour-bar key: one block per category in its own colour, named.

:func:`brainpainter.media.colorbar.draw_colorbar` draws it in the bar's place when the
scale carries categories (``ColourScale.categories``, set for label maps such as a
``.annot``): a gradient of category numbers would mean nothing.

The key's work is bounded before matplotlib lays it out: names are shortened to
:data:`~brainpainter.media.plain_text.MAX_NAME_CHARS` characters, and a key of more
than :data:`MAX_NAMED_CATEGORIES` categories is summarised (its colour blocks, one
line saying how many categories there are, no name per block): thousands of names
cannot be read in a bar and took minutes to lay out.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from brainpainter.media.plain_text import MAX_NAME_CHARS, plain, plain_lines

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.axis import Axis

    from brainpainter.color.scale import ColourScale

#: Most categories a key names one by one; more are drawn as their blocks with a count.
MAX_NAMED_CATEGORIES = 60


#: The gid of a category key's axes.
CATEGORY_KEY = "category-key"


def draw_category_key(ax: Axes, scale: ColourScale, horizontal: bool, fontsize: float, color: Any,
                      label: str | None) -> Axes:
    """A label map's key in the bar's place: one block per category in its colour, named."""
    import numpy as np

    names = [plain(name, MAX_NAME_CHARS) for name, _ in scale.categories]
    ax.set_gid(CATEGORY_KEY)  # its names are never thinned (:mod:`brainpainter.media.tick_labels`)
    colors = np.array([rgb for _, rgb in scale.categories], dtype=float)
    n = len(names)
    ax.imshow(colors[None, :, :] if horizontal else colors[::-1, None, :], extent=(0.0, 1.0, 0.0, 1.0),
              aspect="auto", interpolation="nearest", origin="upper")
    summarised = n > MAX_NAMED_CATEGORIES
    if summarised:  # one tick in the middle saying how many: names of thousands cannot be read in a bar
        where, names = np.array([0.5]), [f"{n} categories"]
    else:
        where = (np.arange(n) + 0.5) / n
    # names too many or too long to sit side by side stand upright
    upright = horizontal and len(names) * max(len(name) for name in names) > 60
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
    if not summarised:
        for edge in np.arange(1, n) / n:  # a thin line between blocks of similar colour
            (ax.axvline if horizontal else ax.axhline)(edge, color=color, linewidth=0.4)
    ax.tick_params(labelsize=max(fontsize - 1 - (2 if len(names) > 20 else 0), 4), length=2.5, width=0.6,
                   pad=1.5, colors=color)
    for spine in ax.spines.values():
        spine.set_linewidth(0.6)
        spine.set_edgecolor(color)
    if label:
        axis.set_label_text(plain_lines(label), fontsize=fontsize, color=color)
    return ax
