"""Tick labels of a colour bar that never overprint: where the laid-out bar is too short for all of them,
fewer are shown, the ends kept and the others evenly spaced between them (issue 44: a connectome
figure's edge bar printed ``-0.75-0.250.250.75``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from brainpainter.media.category_key import CATEGORY_KEY

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

#: Least gap between two tick labels, as a share of their font size (a space's width).
MIN_GAP_EM = 0.4


def thin_tick_labels(ax: Axes, renderer: Any) -> None:
    """Hide tick labels of the bar `ax` (laid out; `renderer`: its figure's) until no two of those shown
    overlap or nearly touch.

    The axis with tick labels (x: a horizontal bar, y: an upright one) keeps its first and last and
    those evenly spaced between them: 5 ticks that overlap become 3 (ends and middle), then 2; 4 become 2.
    """
    if ax.get_gid() == CATEGORY_KEY:  # a key names every category
        return
    for axis, along in ((ax.xaxis, 0), (ax.yaxis, 1)):
        texts = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
        if len(texts) < 3:
            continue
        boxes = [t.get_window_extent(renderer) for t in texts]
        gap = float(renderer.points_to_pixels(MIN_GAP_EM * float(texts[0].get_fontsize())))
        spans = np.array([(b.x0, b.x1) if along == 0 else (b.y0, b.y1) for b in boxes])
        order, n = np.argsort(spans[:, 0]), len(texts)
        for m in [m for m in range(n, 1, -1) if (n - 1) % (m - 1) == 0]:  # evenly spaced: every k-th
            keep = order[np.arange(0, n, (n - 1) // (m - 1))]
            kept = spans[keep]
            if (kept[1:, 0] - kept[:-1, 1] >= gap).all():
                break
        for i, t in enumerate(texts):
            t.set_visible(bool(i in set(keep.tolist())))
