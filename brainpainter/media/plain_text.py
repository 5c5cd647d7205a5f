"""User text drawn as text: the one place a user's string enters matplotlib.

matplotlib reads a string with an even number of ``$`` as mathtext (TeX-like
markup), so a label ``$\\undefinedmacro$`` fails the figure and ``$`` + 98 ``{``
recurses; a title, a colour-bar label, an image name or a category name is the
user's text, never markup. :func:`plain` escapes every ``$`` (matplotlib draws
``\\$`` as a literal dollar sign), drops control characters, and can shorten a
string to a number of characters.
"""

from __future__ import annotations

import functools
import re
import warnings
from collections.abc import Callable
from typing import Any, TypeVar, cast

F = TypeVar("F", bound=Callable[..., Any])

_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")
#: Most characters of one name in a label map's key (a longer one ends with an ellipsis).
MAX_NAME_CHARS = 40


def plain(text: str, max_chars: int | None = None) -> str:
    """`text` as matplotlib draws it literally: ``$`` escaped, control characters (newlines too) as
    spaces, at most `max_chars` characters (the last an ellipsis) where given."""
    shown = _CONTROL.sub(" ", str(text))
    if max_chars is not None and len(shown) > max_chars:
        shown = shown[:max(1, max_chars - 1)] + "\u2026"
    return shown.replace("$", r"\$")


def plain_lines(text: str) -> str:
    """As :func:`plain`, keeping newlines (a title of several lines)."""
    return "\n".join(plain(line) for line in str(text).split("\n"))


def quiet_glyphs(func: F) -> F:
    """Run `func` without matplotlib's "Glyph ... missing from font" warnings.

    Image names in any script (``患者 1``) are drawn in figures and movies; where the fonts lack a glyph
    matplotlib warns once per character (the name is still in the file name and manifest).
    """
    @functools.wraps(func)
    def run(*args: Any, **kwargs: Any) -> Any:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=r"Glyph \d+ .*missing from", category=UserWarning)
            return func(*args, **kwargs)
    return cast(F, run)
