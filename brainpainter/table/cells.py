"""Cell values: what counts as a number, an empty cell, and a decimal comma.

A cell is a number (``1.5``, ``-2e-3``, ``1,5`` in a ``;``- or tab-separated
file), empty (``""``, ``NaN``, ``NA``, ``N/A``, ``#N/A``, ``NULL``, ``None``:
drawn in the no-data colour), or wrong (anything else, and infinities).
"""

from __future__ import annotations

import math
import re

EMPTY = frozenset({"", "nan", "na", "n/a", "#n/a", "null", "none", "-nan", "+nan"})
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_DECIMAL_COMMA = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
_INF = frozenset({"inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"})


def to_number(cell: object, decimal_comma: bool = False) -> float | None:
    """The number in `cell`: a float (NaN when empty, possibly infinite), or None when not a number.

    Parameters
    ----------
    cell : str, float, int or None
    decimal_comma : bool
        Accept ``1,5`` as 1.5 (``;``- and tab-separated exports of European spreadsheets).
    """
    if cell is None:
        return math.nan
    if isinstance(cell, bool):
        return None
    if isinstance(cell, int | float):
        return float(cell)
    text = str(cell).strip()
    if _NUMBER.fullmatch(text):
        return float(text)  # may overflow to inf ("1e999"): the caller reports it
    low = text.lower()
    if low in EMPTY:
        return math.nan
    if low in _INF:
        return math.inf if not low.startswith("-") else -math.inf
    if decimal_comma and _DECIMAL_COMMA.fullmatch(text):
        return float(text.replace(",", "."))
    return None


def is_empty(cell: object) -> bool:
    """Whether `cell` is an empty cell (no data)."""
    if cell is None:
        return True
    if isinstance(cell, float):
        return math.isnan(cell)
    return isinstance(cell, str) and cell.strip().lower() in EMPTY


def is_text(cell: object) -> bool:
    """Whether `cell` holds text that is neither a number nor empty."""
    return isinstance(cell, str) and not is_empty(cell) and to_number(cell, True) is None
