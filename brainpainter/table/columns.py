"""One input table read into value columns: image names, cells to numbers, the three layouts.

:func:`read_part` takes a :class:`~brainpainter.io.rawtable.RawTable` whose
layout :func:`brainpainter.table.shape.detect_shape` found (wide, long or
transposed) and gives one column of values per region key, with the image
names, the cells that are not numbers (:class:`CellProblem`) and notes for
``brainpainter check``. :mod:`brainpainter.table.region_table` merges the
parts of several inputs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.output import MAX_IMAGE_NAME, file_key, same_file_phrase
from brainpainter.io.rawtable import RawTable, has_control
from brainpainter.table.cells import is_empty, to_number
from brainpainter.table.names import REGION, NameResolver, Resolution
from brainpainter.table.shape import TableShape

MAX_PROBLEMS = 50

#: How one input name was understood (with the input it came from): see
#: :class:`brainpainter.table.names.Resolution`.
NameReport = Resolution


@dataclass(frozen=True)
class CellProblem:
    """A cell that stops the table from rendering: not a number, or infinite.

    Attributes
    ----------
    message : str
        The one-line error ``read_table`` raises for it.
    """

    source: str
    where: str
    column: str
    value: str
    problem: str
    message: str


# -- one input ---------------------------------------------------------------------
@dataclass
class Part:
    source: str
    format: str
    shape: TableShape
    images: list[str]
    numbered: bool
    columns: dict[str, tuple[NDArray[Any], str]]  # key -> (values per image, input name)
    names: list[NameReport]
    problems: list[CellProblem]
    notes: list[str]


def _check_name(text: str, source: str, where: str, what: str) -> None:
    if has_control(text):
        raise BrainPainterError(
            f"{source}: the {what} at {where} contains control characters ({text[:40]!r}); names may hold "
            "letters, digits, spaces and punctuation only."
        )


def _image_names(raw: RawTable, shape: TableShape) -> tuple[list[str], bool]:
    if shape.image_index is None:
        return [str(i + 1) for i in range(len(raw.rows))], True
    j = shape.image_index
    out = []
    for row in raw.rows:
        cell = row[j]
        if isinstance(cell, float) and cell.is_integer():
            cell = int(cell)
        out.append("" if cell is None else str(cell).strip())
    validate_images(out, raw.source, [raw.where(i) for i in range(len(out))], shape.image_column or "")
    return out, False


def validate_images(images: list[str], source: str, where: list[str], column: str) -> None:
    seen: dict[str, int] = {}
    folded: dict[str, int] = {}
    for i, name in enumerate(images):
        if not name:
            raise BrainPainterError(
                f"{source}: {where[i]} has an empty image name in {column!r}; give every image a name."
            )
        _check_name(name, source, where[i], "image name")
        if len(name) > MAX_IMAGE_NAME:
            raise BrainPainterError(
                f"{source}: the image name at {where[i]} is {len(name)} characters long; at most "
                f"{MAX_IMAGE_NAME} are allowed. Shorten it."
            )
        if name in seen:
            raise BrainPainterError(
                f"{source}: image names must be unique; {name!r} appears at {where[seen[name]]} and "
                f"{where[i]}."
            )
        if file_key(name) in folded:
            other = images[folded[file_key(name)]]
            raise BrainPainterError(
                f"{source}: image names {same_file_phrase(other, name)}, so their files would "
                "collide on macOS and Windows; make them differ in letters or digits."
            )
        seen[name] = i
        folded[file_key(name)] = i


def _convert(cells: Sequence[Any], raw: RawTable, column: str, rows: Sequence[int],
             problems: list[CellProblem], decimal: list[Any]) -> NDArray[Any]:
    out = np.full(len(cells), np.nan)
    decimal_at: dict[str, tuple[str, str, str]] = decimal[1]  # first cell with a decimal comma / point
    for k, cell in enumerate(cells):
        v = to_number(cell, raw.decimal_comma)
        if v is None:
            problem = "not a number"
            hint = ("; the row repeats the header (two tables pasted together?)"
                    if str(cell).strip() == column else "")
            msg = (f"{raw.source}: column {column!r} {raw.where(rows[k])} holds {str(cell)[:60]!r}, which is "
                   f"not a number{hint}; cells must be numbers or empty (empty = no data).")
        elif math.isinf(v):
            problem = "infinite"
            msg = (f"{raw.source}: column {column!r} {raw.where(rows[k])} is infinite ({str(cell)[:30]!r}); "
                   "cells must be finite numbers or empty (empty = no data).")
        else:
            if raw.decimal_comma and isinstance(cell, str):
                if "," in cell:
                    decimal[0] = True
                    decimal_at.setdefault("comma", (str(cell).strip(), raw.where(rows[k]), column))
                elif "." in cell:
                    decimal_at.setdefault("point", (str(cell).strip(), raw.where(rows[k]), column))
            out[k] = v
            continue
        if len(problems) < MAX_PROBLEMS:
            problems.append(CellProblem(raw.source, raw.where(rows[k]), column, str(cell)[:60], problem, msg))
        elif len(problems) == MAX_PROBLEMS:
            problems.append(CellProblem(
                raw.source, "", column, "", "more",
                f"{raw.source}: more than {MAX_PROBLEMS} bad cells; fix the ones listed."))
    return out


class _Columns:
    """Region key -> (values per image, input name), refusing a second value for one region."""

    def __init__(self, source: str, what: str) -> None:
        self.source, self.what = source, what
        self.data: dict[str, tuple[NDArray[Any], str]] = {}

    def take(self, key: str, values: NDArray[Any], name: str) -> None:
        if key in self.data:
            other = self.data[key][1]
            raise BrainPainterError(
                f"{self.source}: {self.what} {other!r} and {name!r} both name region {key!r}; keep one."
            )
        self.data[key] = (values, name)


def read_part(raw: RawTable, shape: TableShape, resolver: NameResolver) -> Part:
    source = raw.source
    if not raw.rows:
        raise BrainPainterError(
            f"{source} has a header but no rows; add one row per image (or per region)."
        )
    for j, h in enumerate(raw.header):
        _check_name(h, source, f"column {j + 1}", "column name")
    problems: list[CellProblem] = []
    decimal: list[Any] = [False, {}]
    names: list[NameReport] = []
    columns = _Columns(source, "columns" if shape.kind == "wide" else "names")
    empty_columns: list[str] = []
    if shape.kind == "wide":
        images, numbered = _image_names(raw, shape)
        seen_names: set[str] = set()
        for j, h in enumerate(raw.header):
            if j == shape.image_index:
                continue
            if h == "" and all(is_empty(row[j]) for row in raw.rows):
                continue  # a blank column of a spreadsheet export
            r = resolver.lookup(h)
            if h in seen_names and r.status != REGION:
                continue
            seen_names.add(h)
            names.append(replace(r, source=source))
            if r.status != REGION:
                continue
            vals = _convert([row[j] for row in raw.rows], raw, h, range(len(raw.rows)), problems, decimal)
            if not np.isfinite(vals).any() and not any(p.column == h for p in problems):
                empty_columns.append(h)
            for key in r.keys:
                columns.take(key, vals, h)
    elif shape.kind == "long":
        names, images = _read_long(raw, shape, resolver, problems, decimal, columns)
        numbered = False
    else:
        names, images = _read_transposed(raw, shape, resolver, problems, decimal, columns)
        numbered = False
    notes = []
    if empty_columns:
        notes.append(f"{source}: {len(empty_columns)} column(s) have no value in any row ({empty_columns[:3]}"
                     f"{'...' if len(empty_columns) > 3 else ''}); their regions are drawn in the NaN colour")
    at = decimal[1]
    if "comma" in at and "point" in at:
        (c_text, c_where, c_col), (p_text, p_where, p_col) = at["comma"], at["point"]
        raise BrainPainterError(
            f"{source}: decimal commas ({c_text!r}, column {c_col!r} {c_where}) and decimal points "
            f"({p_text!r}, column {p_col!r} {p_where}) are mixed, so {p_text!r} could mean "
            f"{p_text.replace('.', '')!r} (a thousands point); save the table with one decimal separator."
        )
    if decimal[0]:
        notes.append(f"{source}: decimal commas read as decimal points")
    return Part(source, raw.format, shape, images, numbered, columns.data, names, problems, notes)


def _read_long(raw: RawTable, shape: TableShape, resolver: NameResolver, problems: list[CellProblem],
               decimal: list[bool], columns: _Columns) -> tuple[list[NameReport], list[str]]:
    reg, val, img = shape.region_index, shape.value_index, shape.image_index
    assert reg is not None and val is not None
    value_name = shape.value_column or "value"
    lookups: dict[str, Any] = {}
    names: list[NameReport] = []
    images: list[str] = []
    image_where: list[str] = []
    image_pos: dict[str, int] = {}
    cells: dict[str, list[tuple[int, int]]] = {}  # key -> [(image index, row)]
    first_name: dict[str, str] = {}
    origin: dict[tuple[str, int], str] = {}
    for i, row in enumerate(raw.rows):
        cell = row[reg]
        if is_empty(cell):
            continue
        name = str(cell).strip()
        if name not in lookups:
            _check_name(name, raw.source, raw.where(i), "region name")
            r = resolver.lookup(name)
            lookups[name] = r
            names.append(replace(r, source=raw.source))
        r = lookups[name]
        if r.status != REGION:
            continue
        if img is None:
            image = value_name
        else:
            c = row[img]
            if isinstance(c, float) and c.is_integer():
                c = int(c)
            image = "" if c is None else str(c).strip()
        if image not in image_pos:
            image_pos[image] = len(images)
            images.append(image)
            image_where.append(raw.where(i))
        k = image_pos[image]
        for key in r.keys:
            if (key, k) in origin:
                hint = "" if img is not None else "; with several images per region give --image-column"
                raise BrainPainterError(
                    f"{raw.source}: region {key!r} appears twice for image {image!r} ({origin[(key, k)]} and "
                    f"{raw.where(i)}){hint}."
                )
            origin[(key, k)] = raw.where(i)
            cells.setdefault(key, []).append((k, i))
            first_name.setdefault(key, name)
    if img is not None:
        validate_images(images, raw.source, image_where, shape.image_column or "")
    converted: dict[int, float] = {}
    for key, pairs in cells.items():
        todo = [i for _, i in pairs if i not in converted]
        vals = _convert([raw.rows[i][val] for i in todo], raw, value_name, todo, problems, decimal)
        converted.update(zip(todo, vals.tolist(), strict=True))
        arr = np.full(len(images), np.nan)
        for k, i in pairs:
            arr[k] = converted[i]
        columns.take(key, arr, first_name[key])
    return names, images


def _read_transposed(raw: RawTable, shape: TableShape, resolver: NameResolver, problems: list[CellProblem],
                     decimal: list[bool], columns: _Columns) -> tuple[list[NameReport], list[str]]:
    reg = shape.region_index
    assert reg is not None  # a transposed table has its regions in one column
    images = [h for j, h in enumerate(raw.header) if j != reg]
    validate_images(images, raw.source, [f"column {j + 1}" for j in range(len(raw.header)) if j != reg],
                     "header")
    names: list[NameReport] = []
    for i, row in enumerate(raw.rows):
        cell = row[reg]
        if is_empty(cell):
            continue
        name = str(cell).strip()
        _check_name(name, raw.source, raw.where(i), "region name")
        r = resolver.lookup(name)
        names.append(replace(r, source=raw.source))
        if r.status != REGION:
            continue
        vals = _convert([c for j, c in enumerate(row) if j != reg], raw, name, [i] * (len(row) - 1),
                        problems, decimal)
        for key in r.keys:
            columns.take(key, vals, name)
    return names, images
