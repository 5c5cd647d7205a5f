"""Detect a table's shape: wide, long (tidy) or transposed, and its special columns.

* **wide**: one row per image, one column per region (BrainPainter,
  ``aparcstats2table``, ``asegstats2table``, ENIGMA per-subject tables).
  The image names are in ``Image-name-unique``, a column chosen with
  ``--image-column``, a FreeSurfer first column (``lh.aparc.thickness``,
  ``Measure:volume``), a DataFrame index, or a column called ``subject``,
  ``SubjID``, ``participant_id``...; without one, rows are numbered.
* **long**: one row per region (and image): a region column (``Structure``,
  auto-detected when exactly one column holds region names) and a value column
  (``--value``, automatic when only one column is numeric), optionally an
  image column (ENIGMA summary statistics).
* **transposed**: regions as rows and images as columns, as written by
  ``aparcstats2table --transpose``: first header ``lh.aparc.thickness``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from brainpainter.errors import (
    AmbiguousColumnError,
    BrainPainterError,
    ColumnNotFoundError,
    NoRegionColumnError,
    nearest,
)
from brainpainter.io.rawtable import Cell, RawTable
from brainpainter.table.cells import is_empty, is_text, to_number
from brainpainter.table.names import REGION, UNMATCHED, NameResolver

IMAGE_COLUMN = "Image-name-unique"
IMAGE_COLUMN_NAMES = ("image-name-unique", "image", "image_name", "subjid", "subject", "subject_id",
                      "subjectid", "participant_id", "participant", "id")
REGION_COLUMN_NAMES = ("structure", "region", "region_name", "roi", "label", "name", "parcel")
FS_APARC = re.compile(
    r"[lr]h\.[\w.\-]+\.(thickness|thicknessstd|area|volume|meancurv|gauscurv|foldind|curvind)", re.I)
FS_ASEG = re.compile(r"Measure:\w+", re.I)
SAMPLE_ROWS = 2000


@dataclass(frozen=True)
class TableShape:
    """How a table is laid out.

    Attributes
    ----------
    kind : {"wide", "long", "transposed"}
    header : tuple of str
        The table's column names.
    image_index, region_index, value_index : int or None
        Columns with image names, region names (long/transposed) and values (long).
    why : str
        How the layout was recognised, for reports.
    flavour : str
        The producing tool recognised (``"FreeSurfer aparcstats2table"``), or ``""``.
    """

    kind: str
    header: tuple[str, ...]
    image_index: int | None = None
    region_index: int | None = None
    value_index: int | None = None
    why: str = ""
    flavour: str = ""

    def _name(self, i: int | None) -> str | None:
        return None if i is None else self.header[i]

    @property
    def image_column(self) -> str | None:
        return self._name(self.image_index)

    @property
    def region_column(self) -> str | None:
        return self._name(self.region_index)

    @property
    def value_column(self) -> str | None:
        return self._name(self.value_index)

    def describe(self) -> str:
        """One phrase: ``wide (one row per image; images in 'Image-name-unique')``."""
        images = f"images in {self.image_column!r}" if self.image_column else "rows numbered"
        if self.kind == "wide":
            text = f"wide (one row per image, one column per region; {images})"
        elif self.kind == "long":
            text = (f"long (one row per region; regions in {self.region_column!r}, values in "
                    f"{self.value_column!r}; " + (images if self.image_column else "one image") + ")")
        else:
            text = f"transposed (regions in rows from {self.region_column!r}, one column per image)"
        return text + (f", {self.flavour}" if self.flavour else "")

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "image_column": self.image_column, "region_column": self.region_column,
                "value_column": self.value_column, "flavour": self.flavour, "why": self.why,
                "description": self.describe()}


def find_column(raw: RawTable, name: str, option: str) -> int:
    """Index of the column called `name` (exact, else case-insensitive); errors name the option."""
    exact = [i for i, h in enumerate(raw.header) if h == name.strip()]
    if len(exact) == 1:
        return exact[0]
    if len(exact) > 1:
        raise AmbiguousColumnError(
            f"{option} {name!r}: {raw.source} has {len(exact)} columns of that name; rename them apart."
        )
    folded = [i for i, h in enumerate(raw.header) if h.lower() == name.strip().lower()]
    if len(folded) == 1:
        return folded[0]
    close = nearest(name, raw.header)
    shown = raw.header[:8] + (["..."] if len(raw.header) > 8 else [])
    raise ColumnNotFoundError(
        f"{option} {name!r} is not a column of {raw.source}; its columns are {shown}"
        + (f". Did you mean {close[0]!r}?" if close else ".")
    )


def _sample(raw: RawTable, j: int) -> list[Cell]:
    return [row[j] for row in raw.rows[:SAMPLE_ROWS]]


def region_column_score(raw: RawTable, j: int, resolver: NameResolver) -> float:
    """Share of column `j`'s text cells naming a region or known non-region (0 when none is a region)."""
    texts = [str(c) for c in _sample(raw, j) if is_text(c)]
    if not texts:
        return 0.0
    found = [resolver.lookup(t) for t in dict.fromkeys(texts)]
    if not any(r.status == REGION for r in found):
        return 0.0
    known = {r.name for r in found if r.status != UNMATCHED}
    return sum(t in known for t in texts) / len(texts)


def _is_numeric_column(raw: RawTable, j: int) -> bool:
    cells = [c for c in _sample(raw, j) if not is_empty(c)]
    return bool(cells) and all(to_number(c, raw.decimal_comma) is not None for c in cells)


def _image_column_wide(raw: RawTable, resolver: NameResolver) -> tuple[int | None, str]:
    if raw.index_column is not None:
        return raw.header.index(raw.index_column), f"image names from the {raw.format}'s index"
    lower = [h.lower() for h in raw.header]
    found = [lower.index(name) for name in IMAGE_COLUMN_NAMES
             if name in lower and resolver.lookup(raw.header[lower.index(name)]).status != REGION]
    if len(found) > 1:
        names = [raw.header[j] for j in found]
        raise BrainPainterError(
            f"{raw.source}: columns {names} could both hold the image names; choose one with "
            f"--image-column, e.g. --image-column {names[0]!r}."
        )
    if found:
        return found[0], f"image names in column {raw.header[found[0]]!r}"
    if raw.header and (FS_APARC.fullmatch(raw.header[0]) or FS_ASEG.fullmatch(raw.header[0])):
        return 0, f"subject names in FreeSurfer's first column {raw.header[0]!r}"
    return None, "no image-name column, rows numbered"


def _unique(raw: RawTable, j: int | None, role: str) -> None:
    """Refuse a second column named like column `j` (ignoring case): which one holds the `role` is unclear."""
    if j is None or not raw.header[j].strip():
        return
    key = raw.header[j].strip().casefold()
    same = [k for k, h in enumerate(raw.header) if h.strip().casefold() == key]
    if len(same) > 1:
        a, b = same[:2]
        how = "the same name" if raw.header[a] == raw.header[b] else "the same name ignoring case"
        raise BrainPainterError(
            f"{raw.source}: columns {a + 1} ({raw.header[a]!r}) and {b + 1} ({raw.header[b]!r}) have {how}, "
            f"so it is unclear which holds the {role}; rename or remove one."
        )


def detect_shape(raw: RawTable, resolver: NameResolver, *, image_column: str | None = None,
                 region_column: str | None = None, value_column: str | None = None) -> TableShape:
    """Recognise the layout of `raw`.

    Parameters
    ----------
    raw : RawTable
    resolver : NameResolver
        For telling region names from other text.
    image_column, region_column, value_column : str, optional
        ``--image-column``, ``--region-column`` and ``--value``; giving
        `region_column` or `value_column` means a long table.

    Returns
    -------
    TableShape
    """
    header = tuple(raw.header)
    img = find_column(raw, image_column, "--image-column") if image_column is not None else None
    if region_column is not None or value_column is not None:
        return _long(raw, resolver, img, region_column, value_column)
    heads = [resolver.lookup(h) for h in header]
    n_region_heads = sum(r.status == REGION for r in heads)
    first = header[0] if header else ""
    fs_first = bool(FS_APARC.fullmatch(first) or FS_ASEG.fullmatch(first))
    if n_region_heads == 0 and fs_first and raw.rows and region_column_score(raw, 0, resolver) >= 0.5:
        return TableShape("transposed", header, region_index=0,
                          why=f"FreeSurfer table written with --transpose (first column {first!r})",
                          flavour="FreeSurfer " + ("asegstats2table" if first.lower().startswith("measure:")
                                                   else "aparcstats2table") + " --transpose")
    if n_region_heads > 0:
        if img is None:
            img, why = _image_column_wide(raw, resolver)
        else:
            why = f"image names in column {header[img]!r} (--image-column)"
        _unique(raw, img, "image names")
        return TableShape("wide", header, image_index=img,
                          why=f"{n_region_heads} column name(s) name regions; {why}")
    return _long(raw, resolver, img, None, None)


def _long(raw: RawTable, resolver: NameResolver, img: int | None, region_column: str | None,
          value_column: str | None) -> TableShape:
    header = tuple(raw.header)
    why = []
    if region_column is not None:
        reg = find_column(raw, region_column, "--region-column")
        why.append(f"regions in {header[reg]!r} (--region-column)")
    else:
        scores = {j: region_column_score(raw, j, resolver) for j in range(len(header)) if j != img}
        candidates = [j for j, s in scores.items() if s >= 0.5]
        if len(candidates) > 1:
            named = [j for j in candidates if header[j].lower() in REGION_COLUMN_NAMES]
            candidates = named if len(named) == 1 else candidates
        if not candidates:
            names = [h for j, h in enumerate(header)
                     if j != img and str(h).strip() and str(h).lower() not in IMAGE_COLUMN_NAMES]
            raise NoRegionColumnError(
                f"{raw.source}: no column names a {resolver.atlas.name} region, nor does any column hold "
                f"region names (the columns: {resolver.closest_each(names)}); use region names like "
                f"{resolver.atlas.keys[:2]} as column names, or give a long table's region column with "
                "--region-column."
            )
        if len(candidates) > 1:
            raise BrainPainterError(
                f"{raw.source}: columns {[header[j] for j in candidates]} all hold region names; choose the "
                "region column with --region-column."
            )
        reg = candidates[0]
        why.append(f"column {header[reg]!r} holds region names")
    if img is None:
        if raw.index_column is not None:
            img = header.index(raw.index_column)
        else:
            lower = [h.lower() for h in header]
            if IMAGE_COLUMN.lower() in lower and lower.index(IMAGE_COLUMN.lower()) != reg:
                img = lower.index(IMAGE_COLUMN.lower())
    if img == reg:
        raise BrainPainterError(
            f"{raw.source}: column {header[reg]!r} cannot hold both the image names and the region names; "
            "give different --image-column and --region-column."
        )
    if value_column is not None:
        val = find_column(raw, value_column, "--value")
        why.append(f"values in {header[val]!r} (--value)")
    else:
        numeric = [j for j in range(len(header)) if j not in (reg, img) and _is_numeric_column(raw, j)]
        if not numeric:
            raise BrainPainterError(
                f"{raw.source}: a long table with regions in {header[reg]!r} but no column of numbers; "
                "add one, or name the value column with --value."
            )
        for j in numeric:
            _unique(raw, j, "values")
        if len(numeric) > 1:
            names = [header[j] for j in numeric]
            shown = names[:8] + (["..."] if len(names) > 8 else [])
            raise BrainPainterError(
                f"{raw.source}: a long table with regions in {header[reg]!r} and several value columns "
                f"{shown}; choose one with --value, e.g. --value {names[0]!r}."
            )
        val = numeric[0]
        why.append(f"the only numeric column {header[val]!r} holds the values")
    if val in (reg, img):
        raise BrainPainterError(
            f"{raw.source}: --value {header[val]!r} is also the region or image column; choose the column "
            "with the numbers."
        )
    for col, role in ((img, "image names"), (reg, "region names"), (val, "values")):
        _unique(raw, col, role)
    return TableShape("long", header, image_index=img, region_index=reg, value_index=val, why="; ".join(why))
