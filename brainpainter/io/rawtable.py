"""The raw table (cells as read, before region names are resolved) and the limits on reading.

Memory is bounded by refusing inputs larger than :data:`MAX_BYTES` before
reading them; the limit can be raised with the environment variable
``BRAINPAINTER_MAX_INPUT_MB`` (:func:`max_bytes`).
"""

from __future__ import annotations

import math
import os
import re
import unicodedata
from dataclasses import dataclass, field

from brainpainter.errors import BrainPainterError

MAX_BYTES = 32 * 1024 * 1024
MAX_COLUMNS = 16_384  # Excel's own limit; a region table has a few hundred at most
MAX_ROWS = 1_000_000  # rows of a sheet (Excel's own limit is 1,048,576)
MAX_CELLS = 1_000_000  # cells of a sheet (a region table has far fewer); read in a few seconds
MAX_UNZIPPED = 8  # an .xlsx may expand to at most this many times MAX_BYTES
TEXT_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", "")
EXCEL_SUFFIXES = (".xlsx", ".xlsm")

Cell = str | float | int | None


#: Largest BRAINPAINTER_MAX_INPUT_MB accepted (1 TB): beyond it a limit is no limit.
MAX_LIMIT_MB = 1_000_000


def max_bytes() -> int:
    """The input size limit in bytes (``BRAINPAINTER_MAX_INPUT_MB`` overrides :data:`MAX_BYTES`)."""
    text = os.environ.get("BRAINPAINTER_MAX_INPUT_MB", "").strip()
    if not text:
        return MAX_BYTES
    try:
        mb = float(text)
    except ValueError:
        mb = math.nan
    if not 0 < mb <= MAX_LIMIT_MB:  # also NaN and infinity
        raise BrainPainterError(
            f"BRAINPAINTER_MAX_INPUT_MB must be a number of megabytes greater than 0 and at most "
            f"{MAX_LIMIT_MB} (e.g. 64); {text[:40]!r} was given. Set it to a number, or unset it for the "
            f"default of {MAX_BYTES // 2**20} MB."
        )
    return max(1, int(mb * 1024 * 1024))


@dataclass
class RawTable:
    """A table as read, before any region names are resolved.

    Attributes
    ----------
    header : list of str, length n_columns
        Column names, stripped; may repeat or be empty.
    rows : list of list, shape (n_rows, n_columns)
        Cells: ``str`` (text files), ``float``/``int``/``str``/``None``
        (Excel, DataFrames, dicts).
    source : str
        Where it came from, for messages (a path, ``"DataFrame"``, ...).
    format : str
        Human description (``"CSV, ';'-separated, decimal comma, UTF-8 with BOM"``).
    decimal_comma : bool
        Text cells like ``1,5`` mean 1.5.
    index_column : str or None
        Column made from a DataFrame index or dict keys: the image names.
    first_line : int
        File line of the first data row (for messages); 0 when not a file.
    """

    header: list[str]
    rows: list[list[Cell]]
    source: str
    format: str
    decimal_comma: bool = False
    index_column: str | None = None
    first_line: int = 0
    line_of_row: list[int] = field(default_factory=list)

    def where(self, i: int) -> str:
        """Human position of data row `i` (0-based): ``line 7`` in files, ``row 6`` otherwise."""
        if self.line_of_row:
            return f"line {self.line_of_row[i]}"
        return f"row {i + 1}"


def too_big(name: str, size: int, limit: int) -> BrainPainterError:
    return BrainPainterError(
        f"input {name!r} is {size / 2**20:.1f} MB; at most {limit / 2**20:.0f} MB is read, to keep memory "
        "bounded. Split the table, or raise the limit with BRAINPAINTER_MAX_INPUT_MB."
    )


# C0/C1 controls, line separators, and invisible format characters: zero-width spaces and joiners,
# text-direction marks, embeddings, overrides and isolates (a "bidi override" makes a name read
# differently from what it is), the word joiner and a byte-order mark inside the text.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200b-\u200f\u2028-\u202e\u2060-\u2069\ufeff]")


def is_emoji_joiner(text: str, i: int) -> bool:
    """Whether ``text[i]`` is a zero-width joiner inside an emoji sequence (👨‍👩‍👧), which is allowed."""
    if text[i] != "\u200d" or i == 0 or i + 1 >= len(text):
        return False
    before = text[i - 2] if text[i - 1] == "\ufe0f" and i >= 2 else text[i - 1]
    return all(unicodedata.category(c) in ("So", "Sk") for c in (before, text[i + 1]))


def has_control(text: str) -> bool:
    """Whether `text` holds control characters (terminal escapes, NUL, line breaks, bidi overrides).

    A zero-width joiner between two emoji is part of the emoji, not a control character.
    """
    return any(not is_emoji_joiner(text, m.start()) for m in _CONTROL.finditer(text))
