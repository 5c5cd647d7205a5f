"""Excel ``.xlsx`` tables: the first sheet's cached values, with limits against zip bombs.

Formulas are read as the values Excel cached when the file was saved; a
sheet with formulas but no cached values is refused (it would read as empty).
"""

from __future__ import annotations

import io
import zipfile
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.io.rawtable import (
    MAX_CELLS,
    MAX_COLUMNS,
    MAX_ROWS,
    MAX_UNZIPPED,
    Cell,
    RawTable,
    max_bytes,
)


def read_xlsx(raw: bytes, source: str) -> RawTable:
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
