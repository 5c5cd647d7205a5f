"""Read tables from files, bytes, DataFrames and dicts into one raw form.

Formats: CSV, TSV, ``;``-separated text with decimal commas (European
spreadsheets), white-space separated text (``aparcstats2table --delimiter
space``) and Excel ``.xlsx``; UTF-8 with or without BOM, UTF-16 with BOM
(Excel "Unicode text"), and Windows-1252 as a fallback for non-UTF-8 text.
The format is sniffed from the content, so a wrong file extension is caught.

Memory is bounded by refusing inputs larger than :data:`MAX_BYTES` before
reading them (checked with ``stat`` for files, so a huge file is never
loaded); the limit can be raised with the environment variable
``BRAINPAINTER_MAX_INPUT_MB``. Parsed cells are kept as Python strings: peak
memory is about 10x the file size (see ``docs/inputs.md``).
"""

from __future__ import annotations

import csv
import io
import os
import re
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.errors import BrainPainterError

MAX_BYTES = 32 * 1024 * 1024
MAX_COLUMNS = 16_384  # Excel's own limit; a region table has a few hundred at most
MAX_ROWS = 1_000_000  # rows of a sheet (Excel's own limit is 1,048,576)
MAX_CELLS = 1_000_000  # cells of a sheet (a region table has far fewer); read in a few seconds
MAX_UNZIPPED = 8  # an .xlsx may expand to at most this many times MAX_BYTES
TEXT_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", "")
EXCEL_SUFFIXES = (".xlsx", ".xlsm")

Cell = str | float | int | None


def max_bytes() -> int:
    """The input size limit in bytes (``BRAINPAINTER_MAX_INPUT_MB`` overrides :data:`MAX_BYTES`)."""
    text = os.environ.get("BRAINPAINTER_MAX_INPUT_MB", "").strip()
    if not text:
        return MAX_BYTES
    try:
        mb = float(text)
    except ValueError:
        raise BrainPainterError(
            f"BRAINPAINTER_MAX_INPUT_MB must be a number of megabytes; {text!r} was given."
        ) from None
    return int(mb * 1024 * 1024)


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


# -- entry point -----------------------------------------------------------------
def read_raw(data: Any) -> RawTable:
    """Read one input (path, bytes, binary file object, DataFrame, Series or dict)."""
    if isinstance(data, str | os.PathLike):
        return _read_path(Path(data))
    if isinstance(data, bytes | bytearray | memoryview):
        return parse_bytes(bytes(data), "bytes")
    if hasattr(data, "read") and callable(data.read):
        name = str(getattr(data, "name", "stream"))
        limit = max_bytes()
        raw = data.read(limit + 1)
        if isinstance(raw, str):
            raw = raw.encode("utf-8")
        if len(raw) > limit:
            raise _too_big(name, len(raw), limit)
        return parse_bytes(raw, name, Path(name).suffix.lower())
    module = type(data).__module__ or ""
    if module.startswith("pandas"):
        import pandas as pd

        if isinstance(data, pd.DataFrame):
            return _from_frame(data)
        if isinstance(data, pd.Series):
            return _from_mapping(data.to_dict(), "Series")
    if isinstance(data, Mapping):
        return _from_mapping(data, "dict")
    raise BrainPainterError(
        f"input of type {type(data).__name__} is not supported; give a table file (CSV, TSV, .xlsx), "
        "a pandas DataFrame or a dict of region to value(s)."
    )


def _too_big(name: str, size: int, limit: int) -> BrainPainterError:
    return BrainPainterError(
        f"input {name!r} is {size / 2**20:.1f} MB; at most {limit / 2**20:.0f} MB is read, to keep memory "
        "bounded. Split the table, or raise the limit with BRAINPAINTER_MAX_INPUT_MB."
    )


def _read_path(path: Path) -> RawTable:
    from brainpainter.io.files import read_input

    raw = read_input(path, "input file", max_bytes(), hint="give the path of a table (CSV, TSV or .xlsx)",
                     env="BRAINPAINTER_MAX_INPUT_MB")
    return parse_bytes(raw, str(path), path.suffix.lower())


# -- bytes -------------------------------------------------------------------------
def parse_bytes(raw: bytes, source: str, suffix: str = "") -> RawTable:
    """Parse the bytes of a table file; the format is sniffed from the content.

    Parameters
    ----------
    raw : bytes
    source : str
        Name for messages.
    suffix : str
        File extension (``".csv"``), only to catch misnamed files.
    """
    limit = max_bytes()
    if len(raw) > limit:
        raise _too_big(source, len(raw), limit)
    if not raw.strip():
        raise BrainPainterError(
            f"input {source!r} is empty; it needs a header row and one row per image (or per region)."
        )
    if raw.startswith(b"PK\x03\x04"):
        if suffix not in (*EXCEL_SUFFIXES, ""):
            raise BrainPainterError(
                f"input {source!r} is an Excel workbook (a zip file) although it is named {suffix!r}; "
                "rename it to .xlsx, or export the sheet as CSV."
            )
        return _read_xlsx(raw, source)
    if raw.startswith(b"\xd0\xcf\x11\xe0"):
        raise BrainPainterError(
            f"input {source!r} is an old Excel 97-2003 (.xls) workbook, which is not read; "
            "save it as .xlsx or CSV."
        )
    if raw.startswith(b"\x1f\x8b") or raw.startswith(b"BZh") or raw.startswith(b"\xfd7zXZ"):
        raise BrainPainterError(
            f"input {source!r} is a compressed file; decompress it and give the table inside."
        )
    if suffix in EXCEL_SUFFIXES:
        raise BrainPainterError(
            f"input {source!r} is named {suffix!r} but is not an Excel workbook (no zip signature); "
            "if it is a text table, name it .csv."
        )
    text, encoding = _decode(raw, source)
    return parse_text(text, source, suffix, encoding)


def _decode(raw: bytes, source: str) -> tuple[str, str]:
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16"), "UTF-16"
        except UnicodeDecodeError:
            pass
    elif b"\x00" in raw:
        raise BrainPainterError(
            f"input {source!r} contains NUL bytes: it is binary, not a text table; give a CSV, TSV or "
            ".xlsx table with one column per region."
        )
    if raw.startswith(b"\xef\xbb\xbf"):
        encoding, body = "UTF-8 with BOM", raw[3:]
    else:
        encoding, body = "UTF-8", raw
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError:
        try:
            text, encoding = body.decode("cp1252"), "Windows-1252 (not UTF-8)"
        except UnicodeDecodeError:
            raise BrainPainterError(
                f"input {source!r} is neither UTF-8 nor Windows-1252 text: it is binary or in an unknown "
                "encoding; save it as 'CSV UTF-8'."
            ) from None
    if "\x00" in text:
        raise BrainPainterError(
            f"input {source!r} contains NUL characters: it is binary, not a text table; give a CSV, TSV or "
            ".xlsx table."
        )
    sample = text[:65536]
    controls = sum(1 for ch in sample if ord(ch) < 32 and ch not in "\t\r\n\f")
    if controls > max(2, len(sample) // 100):
        raise BrainPainterError(
            f"input {source!r} is full of control characters: it is binary, not a text table; give a CSV, "
            "TSV or .xlsx table."
        )
    return text, encoding


_SEPARATORS = {"\t": "tab-separated", ";": "';'-separated", ",": "comma-separated", "|": "'|'-separated"}


def _count_outside_quotes(line: str, ch: str) -> int:
    n, quoted = 0, False
    for c in line:
        if c == '"':
            quoted = not quoted
        elif c == ch and not quoted:
            n += 1
    return n


def _sniff_separator(header_line: str, suffix: str) -> str:
    if suffix in (".tsv", ".tab"):
        return "\t"
    counts = {sep: _count_outside_quotes(header_line, sep) for sep in ("\t", ";", ",", "|")}
    best = max(counts, key=lambda s: (counts[s], s == "\t", s == ";", s == ","))
    if counts[best] > 0:
        return best
    return " " if header_line.strip().count(" ") > 0 else ","


def parse_text(text: str, source: str, suffix: str = "", encoding: str = "UTF-8") -> RawTable:
    """Parse decoded table text (separator sniffed from the header line)."""
    if "\r" in text:  # Windows (CR LF) and old Mac (CR) line ends
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")  # not splitlines(): a quoted cell may hold other line separators
    first = next((i for i, line in enumerate(lines) if line.strip()), None)
    if first is None:
        raise BrainPainterError(
            f"input {source!r} has only blank lines; it needs a header row and data rows."
        )
    sep = _sniff_separator(lines[first], suffix)
    rows: list[list[Cell]] = []
    line_of_row: list[int] = []
    if sep == " ":
        parsed = ((i + 1, line.split()) for i, line in enumerate(lines))
        kind = "white-space separated"
    else:
        # Lines fed one by one: io.StringIO would copy the text at 4 bytes per character.
        reader = csv.reader((line + "\n" for line in lines), delimiter=sep, strict=True)
        parsed = _numbered(reader)
        kind = _SEPARATORS[sep]
    header: list[str] | None = None
    try:
        for line_no, fields in parsed:
            if header is None:
                if not any(f.strip() for f in fields):
                    continue
                header = [f.strip() for f in fields]
                while len(header) > 1 and header[-1] == "":
                    header.pop()  # trailing separators of spreadsheet exports
                if len(header) > MAX_COLUMNS:
                    raise BrainPainterError(
                        f"input {source!r} has {len(header)} columns; at most {MAX_COLUMNS} are read. A "
                        "region table has one column per region (a few hundred); put images in rows."
                    )
                continue
            if not any(f.strip() for f in fields):
                continue  # blank line
            if len(fields) != len(header):
                extra = fields[len(header):]
                if len(fields) > len(header) and not any(f.strip() for f in extra):
                    fields = fields[: len(header)]
                else:
                    raise BrainPainterError(
                        f"input {source!r} line {line_no} has {len(fields)} fields but the header has "
                        f"{len(header)}; every row needs one cell per column (check separators and quotes)."
                    )
            rows.append(list(fields))
            line_of_row.append(line_no)
    except csv.Error as exc:
        raise BrainPainterError(
            f"cannot parse {source!r} as a {kind} table ({exc}); check quotes and separators, or save it "
            "again as CSV."
        ) from None
    if header is None:
        raise BrainPainterError(
            f"input {source!r} has no header row, only separators; it needs column names in its first line."
        )
    fmt = f"text, {kind}, {encoding}"
    return RawTable(header, rows, source, fmt, decimal_comma=sep not in (",",), line_of_row=line_of_row)


def _numbered(reader):  # yields (line number where the record starts, fields)
    line = 1
    for fields in reader:
        yield line, fields
        line = reader.line_num + 1


# -- Excel -------------------------------------------------------------------------
def _read_xlsx(raw: bytes, source: str) -> RawTable:
    import warnings

    limit = max_bytes() * MAX_UNZIPPED
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            names = zf.namelist()
            unzipped = sum(max(0, i.file_size) for i in zf.infolist())
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
        raise BrainPainterError(
            f"cannot read {source!r}: it starts like an .xlsx (zip) file but is damaged ({exc}); "
            "open and save it again in a spreadsheet program."
        ) from None
    if "xl/workbook.xml" not in names:
        raise BrainPainterError(
            f"input {source!r} is a zip archive but not an Excel .xlsx workbook; give a CSV, TSV or "
            ".xlsx table."
        )
    if unzipped > limit:
        raise BrainPainterError(
            f"input {source!r} expands to {unzipped / 2**20:.0f} MB when unzipped; at most "
            f"{limit / 2**20:.0f} MB is read. Split the workbook or export the sheet as CSV."
        )
    try:
        from openpyxl import load_workbook
    except ImportError:  # pragma: no cover - openpyxl is a dependency of the test extras
        raise BrainPainterError(
            "reading .xlsx needs openpyxl: pip install openpyxl (or export the sheet as CSV)."
        ) from None
    sheets: list[tuple[str, list[list[Cell]]]] = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            wb = load_workbook(io.BytesIO(raw), read_only=True, data_only=True)
            try:
                for ws in wb.worksheets:
                    rows = _sheet_rows(ws, source)
                    if any(rows):
                        sheets.append((ws.title, rows))
            finally:
                wb.close()
    except BrainPainterError:
        raise
    except Exception as exc:  # openpyxl/zip/XML errors on damaged or hostile files
        first = str(exc).splitlines()[0][:200] if str(exc) else type(exc).__name__
        raise BrainPainterError(
            f"cannot read {source!r} as an Excel workbook ({first}); open and save it again, or export "
            "the sheet as CSV."
        ) from None
    if not sheets:
        raise BrainPainterError(f"input {source!r} is an Excel workbook with no filled cells; it is empty.")
    if len(sheets) > 1:
        names_ = [s[0] for s in sheets]
        raise BrainPainterError(
            f"input {source!r} has {len(sheets)} sheets with data {names_[:5]}; keep the table to paint "
            "alone in the workbook (delete or move the other sheets), or export that sheet as CSV."
        )
    title, rows = sheets[0]
    if _has_formulas(raw):
        _refuse_uncached_formulas(raw, source, title, rows)
    start = next(i for i, r in enumerate(rows) if r)
    header = ["" if v is None else str(v).strip() for v in rows[start]]
    if len(header) > MAX_COLUMNS:
        raise BrainPainterError(
            f"input {source!r} has {len(header)} columns; at most {MAX_COLUMNS} are read."
        )
    body: list[list[Cell]] = []
    line_of_row: list[int] = []
    for i, row in enumerate(rows[start + 1:], start=start + 2):
        if not row:
            continue
        if len(row) > len(header):
            raise BrainPainterError(
                f"input {source!r} sheet {title!r} row {i} has cells beyond the last named column "
                f"({len(header)}); give every column a header or delete the stray cells."
            )
        body.append(row + [None] * (len(header) - len(row)))
        line_of_row.append(i)
    return RawTable(header, body, source, f"Excel workbook, sheet {title!r}", line_of_row=line_of_row)


def _sheet_rows(ws: Any, source: str) -> list[list[Cell]]:
    """The rows of a read-only worksheet, bounded in rows and cells whatever its XML claims."""
    from openpyxl.utils import get_column_letter

    claimed_rows, claimed_cols = ws.max_row or 0, ws.max_column or 0
    if claimed_rows > MAX_ROWS or claimed_cols > MAX_COLUMNS:
        raise BrainPainterError(
            f"input {source!r} sheet {ws.title!r} claims {claimed_rows} rows x {claimed_cols} columns "
            f"(A1:{get_column_letter(max(1, min(claimed_cols, 18278)))}{claimed_rows}); at most {MAX_ROWS} "
            f"rows and {MAX_COLUMNS} columns are read. Open and save it again in a spreadsheet program, or "
            "export the sheet as CSV."
        )
    ws.reset_dimensions()  # rows come as stored, not padded to the claimed size
    rows: list[list[Cell]] = []
    cells = 0
    for row in ws.iter_rows(values_only=True):
        cells += len(row)
        if len(rows) >= MAX_ROWS or cells > MAX_CELLS:
            raise BrainPainterError(
                f"input {source!r} sheet {ws.title!r} has more than {MAX_ROWS} rows or {MAX_CELLS} cells; "
                "a region table has one row per image (or per region and image). Split the workbook or "
                "export the sheet as CSV."
            )
        rows.append(_trim([_xl_cell(v) for v in row]))
    return rows


def _has_formulas(raw: bytes) -> bool:
    """Whether any worksheet of the workbook holds a formula (an ``<f>`` element), read in chunks."""
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        for name in zf.namelist():
            if not name.startswith("xl/worksheets/"):
                continue
            with zf.open(name) as fh:
                tail = b""
                while chunk := fh.read(1 << 20):
                    text = tail + chunk
                    if b"<f>" in text or b"<f " in text or b":f>" in text or b":f " in text:
                        return True
                    tail = text[-8:]
    return False


def _refuse_uncached_formulas(raw: bytes, source: str, title: str, rows: list[list[Cell]]) -> None:
    """Empty cells that hold a formula without a saved result (written by a script, never opened)."""
    from openpyxl import load_workbook

    wb = load_workbook(io.BytesIO(raw), read_only=True, data_only=False)
    try:
        ws = wb[title]
        ws.reset_dimensions()
        for i, (row, values) in enumerate(zip(ws.iter_rows(), rows, strict=False)):
            for j, cell in enumerate(row):
                value = getattr(cell, "value", None)
                cached = values[j] if j < len(values) else None
                if cached is None and (getattr(cell, "data_type", "") == "f" or
                                       (isinstance(value, str) and value.startswith("="))):
                    where = getattr(cell, "coordinate", f"row {i + 1}")
                    raise BrainPainterError(
                        f"input {source!r} sheet {title!r} cell {where} "
                        f"holds the formula {str(value)[:40]!r} without a saved result, so its value is "
                        "unknown; open and save the workbook in a spreadsheet program (which stores the "
                        "results), or export the sheet as CSV."
                    )
    finally:
        wb.close()


def _xl_cell(v: Any) -> Cell:
    if v is None or (isinstance(v, str | float | int) and not isinstance(v, bool)):
        return v
    return str(v)


def _trim(row: list[Cell]) -> list[Cell]:
    end = len(row)
    while end and (row[end - 1] is None or row[end - 1] == ""):
        end -= 1
    return row[:end]


# -- Python objects ------------------------------------------------------------------
def _from_frame(frame: Any) -> RawTable:
    import pandas as pd

    if len(frame.columns) > MAX_COLUMNS:
        raise BrainPainterError(
            f"the DataFrame has {len(frame.columns)} columns; at most {MAX_COLUMNS} are read."
        )
    header = ["_".join(map(str, c)) if isinstance(c, tuple) else str(c).strip() for c in frame.columns]
    index_column = None
    index = frame.index
    if not isinstance(index, pd.RangeIndex) or index.name is not None:
        index_column = str(index.name) if index.name is not None else "index"
        if index_column in header:
            index_column = None
    obj = frame.astype(object)
    obj = obj.where(frame.notna(), None)
    rows = obj.to_numpy().tolist()
    if index_column is not None:
        header = [index_column, *header]
        rows = [[_py(k), *r] for k, r in zip(index.tolist(), rows, strict=True)]
    rows = [[_py(v) for v in r] for r in rows]
    return RawTable(header, rows, "DataFrame", "pandas DataFrame", index_column=index_column)


def _py(v: Any) -> Cell:
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, bool | np.bool_):
        return str(bool(v))
    if isinstance(v, int | np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        return float(v)
    return str(v)


def _from_mapping(data: Mapping[Any, Any], source: str) -> RawTable:
    if len(data) == 0:
        raise BrainPainterError(f"the {source} is empty; give {{region: value}} or {{region: [values]}}.")
    if len(data) > MAX_COLUMNS:
        raise BrainPainterError(f"the {source} has {len(data)} entries; at most {MAX_COLUMNS} are read.")
    values = list(data.values())
    if all(isinstance(v, Mapping) for v in values):
        # {image: {region: value}}
        header: list[str] = list(dict.fromkeys(str(k) for v in values for k in v))
        if len(header) > MAX_COLUMNS:
            raise BrainPainterError(f"the {source} names {len(header)} regions; at most {MAX_COLUMNS}.")
        rows = []
        for image, inner in data.items():
            by = {str(k): _py(v) for k, v in inner.items()}
            rows.append([_py(image) if not isinstance(image, str) else image,
                         *[by.get(h) for h in header]])
        return RawTable(["image", *header], rows, source, f"{source} of dicts (image -> region -> value)",
                        index_column="image")
    if any(isinstance(v, Mapping) for v in values):
        raise BrainPainterError(
            f"the {source} mixes nested dicts and plain values; give {{region: value(s)}} or "
            "{image: {region: value}}."
        )
    columns: list[list[Cell]] = []
    for k, v in data.items():
        if isinstance(v, np.ndarray):
            if v.ndim > 1:
                raise BrainPainterError(
                    f"the {source}'s value for {str(k)!r} has shape {v.shape}; give one value or a 1-D list."
                )
            v = v.tolist()
        if isinstance(v, list | tuple):
            columns.append([_py(x) for x in v])
        else:
            columns.append([_py(v)])
    lengths = sorted({len(c) for c in columns})
    if len(lengths) > 1:
        raise BrainPainterError(
            f"the {source}'s values have different lengths {lengths}; give one value per "
            "region, or equally long lists (one entry per image)."
        )
    header = [str(k).strip() for k in data]
    rows = [list(r) for r in zip(*columns, strict=True)]
    return RawTable(header, rows, source, source)


# C0/C1 controls, line separators, and invisible format characters: zero-width spaces and joiners,
# text-direction marks, embeddings, overrides and isolates (a "bidi override" makes a name read
# differently from what it is), the word joiner and a byte-order mark inside the text.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200b-\u200f\u2028-\u202e\u2060-\u2069\ufeff]")


def has_control(text: str) -> bool:
    """Whether `text` holds control characters (terminal escapes, NUL, line breaks, bidi overrides)."""
    return _CONTROL.search(text) is not None
