"""Rows of the user's table: choosing them by image name or position (``--rows``, ``--row``), and values
between two of them (a movie's frames between key frames)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, nearest


def select_rows(images: Sequence[str], rows: Iterable[str | int] | str | None,
                what: str = "--rows") -> list[int]:
    """Positions of the chosen rows.

    Parameters
    ----------
    images : sequence of str
        The table's image names.
    rows : iterable of str or int, or a comma-separated str, optional
        Image names (exact, else case-insensitive), or ints as 0-based
        positions. None: every row.
    what : str
        The option's name in error messages.

    Returns
    -------
    list of int
    """
    if rows is None:
        return list(range(len(images)))
    items: list[str | int] = ([r for r in rows.split(",") if r.strip()] if isinstance(rows, str)
                              else list(rows))
    folded = {n.lower(): i for i, n in enumerate(images)}
    out: list[int] = []
    for item in items:
        if isinstance(item, int | np.integer) and not isinstance(item, bool):
            if not -len(images) <= int(item) < len(images):
                raise BrainPainterError(
                    f"row {int(item)} does not exist; the table has {len(images)} row(s) (0-based positions)."
                )
            out.append(int(item) % len(images))
            continue
        name = str(item).strip()
        if name in images:
            out.append(images.index(name))
        elif name.lower() in folded:
            out.append(folded[name.lower()])
        else:
            close = nearest(name, images)
            shown = list(images[:8]) + (["..."] if len(images) > 8 else [])
            raise BrainPainterError(
                f"{what}: {name!r} is not an image name of the table; its images are {shown}"
                + (f". Did you mean {close[0]!r}?" if close else ".")
            )
    if not out:
        raise BrainPainterError(f"no row was chosen in {rows!r}; e.g. --rows stage-1,stage-4")
    return list(dict.fromkeys(out))


def interpolate(a: NDArray[Any], b: NDArray[Any], weight: float) -> NDArray[Any]:
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
