"""Parse user colours: names, ``#rrggbb``, 0-1 or 0-255 triples."""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypeAlias

if TYPE_CHECKING:
    from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, nearest

#: A colour as users give it (a string alias: numpy is not imported with this module).
ColorLike: TypeAlias = "str | Sequence[float] | NDArray[Any]"

_HEX = re.compile(r"^#?([0-9a-fA-F]{6})([0-9a-fA-F]{2})?$")
_HELP = (
    "a colour is a name ('red', 'tab:blue'), '#rrggbb', or three numbers "
    "either all in 0-1 (0.5,0.2,0.1) or 0-255 (128,51,25)"
)


#: The commonest colour names (the defaults among them), as matplotlib's CSS4 table has them: these need
#: no matplotlib import (~0.1-0.2 s of a cold start); any other name is looked up in matplotlib.
COMMON_NAMES = {
    "white": "#FFFFFF", "black": "#000000", "red": "#FF0000", "green": "#008000", "blue": "#0000FF",
    "yellow": "#FFFF00", "orange": "#FFA500", "purple": "#800080", "grey": "#808080", "gray": "#808080",
    "cyan": "#00FFFF", "magenta": "#FF00FF", "pink": "#FFC0CB", "brown": "#A52A2A", "navy": "#000080",
    "teal": "#008080", "lightgrey": "#D3D3D3", "lightgray": "#D3D3D3", "darkgrey": "#A9A9A9",
    "darkgray": "#A9A9A9", "silver": "#C0C0C0",
}


def _named_colors() -> dict[str, Any]:
    from matplotlib import colors as mcolors

    return {str(k): v for k, v in mcolors.get_named_colors_mapping().items()}


def to_rgb(color: ColorLike) -> tuple[float, float, float]:
    """Convert a colour to an sRGB triple in 0-1.

    Parameters
    ----------
    color : str or sequence of 3 numbers
        A matplotlib colour name, ``#rrggbb``, ``"r,g,b"``, or a triple.
        Triples with any component above 1 are read as 0-255.

    Returns
    -------
    tuple of float, shape (3,)
    """
    if isinstance(color, str):
        text = color.strip()
        m = _HEX.match(text)
        if m and (text.startswith("#") or not text.isalpha()):
            h = m.group(1)
            return tuple(int(h[i : i + 2], 16) / 255.0 for i in (0, 2, 4))  # type: ignore[return-value]
        if "," in text or " " in text:
            parts = [p for p in re.split(r"[,\s]+", text.strip("()[] ")) if p]
            try:
                return to_rgb([float(p) for p in parts])
            except ValueError:
                raise BrainPainterError(f"colour {color!r} is not valid: {_HELP}.") from None
        key = text.lower()
        if key in COMMON_NAMES:
            return to_rgb(COMMON_NAMES[key])
        names = _named_colors()
        if key in names:
            return to_rgb(names[key])
        close = nearest(key, [n for n in names if ":" not in n or n.startswith("tab:")])
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise BrainPainterError(f"colour {color!r} is not known: {_HELP}.{hint}")
    if isinstance(color, tuple | list) and all(isinstance(c, int | float) for c in color):
        values = [float(c) for c in color]  # plain numbers (the defaults): no numpy needed
    else:
        import numpy as np

        try:
            values = [float(c) for c in np.asarray(color, dtype=float).ravel()]
        except (TypeError, ValueError):
            raise BrainPainterError(f"colour {color!r} is not valid: {_HELP}.") from None
    return _triple(color, values)


def _triple(color: object, arr: list[float]) -> tuple[float, float, float]:
    """`arr` (3 or 4 numbers, 0-1 or 0-255) as an sRGB triple in 0-1; `color` is what the user gave."""
    import math

    if len(arr) == 4:
        arr = arr[:3]
    if len(arr) != 3 or not all(math.isfinite(c) and c >= 0 for c in arr):
        raise BrainPainterError(f"colour {color!r} is not valid: {_HELP}.")
    if any(c > 1 for c in arr):
        if any(c > 255 for c in arr):
            raise BrainPainterError(f"colour {color!r} is out of range: {_HELP}.")
        arr = [c / 255.0 for c in arr]
    return (arr[0], arr[1], arr[2])


def to_hex(rgb: Sequence[float]) -> str:
    """``(r, g, b)`` in 0-1 to ``#rrggbb``."""
    return "#" + "".join(f"{round(float(c) * 255):02x}" for c in rgb[:3])
