"""User-facing errors: one line, what was given, what is allowed, what to do."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


class BrainPainterError(Exception):
    """An error caused by the user's input or environment.

    The CLI prints its message as one line and exits with code 2, without a
    traceback. Library callers can catch it like any exception.
    """

    exit_code = 2


class PluginError(BrainPainterError):
    """A plugin could not be loaded or does not honour its contract."""


# -- error types of the inputs: tables and atlases (issue 13, structure helper) -----------
# Raised where the caller branches on the kind of error, so that it never matches message text.
class NoRegionColumnError(BrainPainterError):
    """No column of a table names a region of the atlas, nor holds region names."""

# -- end of the input errors -------------------------------------------------------------


def nearest(value: str, allowed: Iterable[str], n: int = 1) -> list[str]:
    """Closest matches to `value` among `allowed` (case-insensitive)."""
    allowed = list(allowed)
    lower = {a.lower(): a for a in allowed}
    hits = difflib.get_close_matches(str(value).lower(), list(lower), n=n, cutoff=0.5)
    return [lower[h] for h in hits]


def choice_error(what: str, value: object, allowed: Iterable[str], hint: str = "") -> BrainPainterError:
    """Build the standard "'what' must be one of [...]; 'x' was given" error."""
    allowed = sorted(set(allowed))
    shown = allowed if len(allowed) <= 12 else [*allowed[:12], "..."]
    msg = f"{what} must be one of {shown}; {value!r} was given."
    close = nearest(str(value), allowed)
    if close:
        msg += f" Did you mean {close[0]!r}?"
    if hint:
        msg += f" {hint}"
    return BrainPainterError(msg)


# -- error types of the run options and media (issue 13, options helper) ---------------------------
class ColumnNotFoundError(BrainPainterError):
    """A column named by an option (``--time-column``, ``--image-column``...) is not in a table."""


class AmbiguousColumnError(BrainPainterError):
    """A column named by an option appears more than once in a table."""


def within(value: Any, low: float, high: float) -> bool:
    """Whether `value` is a number (anything ``float()`` takes) from `low` to `high`, inclusive (NaN is
    not): the test behind an option's "must be a number from ... to ..." line."""
    try:
        return low <= float(value) <= high
    except (TypeError, ValueError):
        return False
