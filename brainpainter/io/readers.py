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
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.errors import BrainPainterError
from brainpainter.io.excel import read_xlsx
from brainpainter.io.rawtable import (
    EXCEL_SUFFIXES,
    MAX_COLUMNS,
    Cell,
    RawTable,
    max_bytes,
    too_big,
)


# -- entry point -----------------------------------------------------------------
def read_raw(data: Any) -> RawTable:
    """Read one input (path, bytes, binary file object, DataFrame, Series or dict; a RawTable as it is)."""
    if isinstance(data, RawTable):
        return data
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
            raise too_big(name, len(raw), limit)
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
        raise too_big(source, len(raw), limit)
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
        return read_xlsx(raw, source)
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


def decode_text(raw: bytes, source: str) -> str:
    """The text of a text file's bytes (UTF-8 with or without BOM, UTF-16, Windows-1252); binary refused.

    Raises
    ------
    BrainPainterError
        NUL bytes, control characters throughout, or an unknown encoding.
    """
    return _decode(raw, source)[0]


def sniff_separator(first_line: str, suffix: str = "") -> str:
    """The separator of a table's lines, from its first line: tab, ``;``, ``,``, ``|`` or ``" "`` (white
    space)."""
    return _sniff_separator(first_line, suffix)


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
    parsed: Iterator[tuple[int, list[str]]]
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


def _numbered(reader: Any) -> Iterator[tuple[int, list[str]]]:  # (line where the record starts, fields)
    line = 1
    for fields in reader:
        yield line, fields
        line = reader.line_num + 1


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
