"""Read region-value tables (first pass: the original BrainPainter CSV).

The original format: first column ``Image-name-unique``, then one column per
region (``Left-insula``, ``Right-Hippocampus``, ...), one row per output image
set. A pandas DataFrame or a ``{region: value}`` / ``{region: [values]}`` dict
works the same from Python.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.atlas import Atlas
from brainpainter.errors import BrainPainterError
from brainpainter.regionnames import NameResolver

IMAGE_COLUMN = "Image-name-unique"
MAX_BYTES = 200 * 1024 * 1024


@dataclass(frozen=True)
class RegionTable:
    """Values per image and region, resolved against one atlas.

    Attributes
    ----------
    images : tuple of str
        Image (row) names, unique, in input order.
    regions : tuple of str
        Region keys of the atlas that have a column, in input order.
    values : ndarray of float, shape (n_images, n_regions)
        NaN marks an empty cell.
    atlas : Atlas
    columns : dict of str to str or None
        Every input column and the region key it resolved to (None: unmatched).
    source : str
        Where the table came from (path or "DataFrame").
    """

    images: tuple[str, ...]
    regions: tuple[str, ...]
    values: np.ndarray
    atlas: Atlas
    columns: dict[str, str | None] = field(default_factory=dict)
    source: str = ""

    @property
    def unmatched(self) -> list[str]:
        return [c for c, k in self.columns.items() if k is None]

    @property
    def absent(self) -> list[str]:
        """Atlas regions with no column in the input."""
        have = set(self.regions)
        return [k for k in self.atlas.keys if k not in have]

    def row(self, i: int) -> dict[str, float]:
        """``{region key: value}`` of image `i` (NaN for empty cells)."""
        return dict(zip(self.regions, self.values[i].tolist(), strict=True))

    def summary(self) -> dict[str, Any]:
        """Counts for reports and manifests."""
        finite = self.values[np.isfinite(self.values)]
        return {
            "source": self.source,
            "atlas": self.atlas.name,
            "n_images": len(self.images),
            "n_regions_matched": len(self.regions),
            "n_regions_in_atlas": len(self.atlas),
            "unmatched_columns": self.unmatched,
            "regions_without_value": self.absent,
            "n_empty_cells": int(np.isnan(self.values).sum()),
            "value_range": [float(finite.min()), float(finite.max())] if finite.size else None,
        }

    def summary_line(self) -> str:
        s = self.summary()
        rng = s["value_range"]
        rng_text = f"values {rng[0]:g}..{rng[1]:g}" if rng else "no values"
        return (
            f"{s['n_images']} image(s), {s['n_regions_matched']}/{s['n_regions_in_atlas']} "
            f"{self.atlas.name} regions matched, {len(s['unmatched_columns'])} column(s) unmatched, "
            f"{s['n_empty_cells']} empty cell(s), {rng_text}"
        )


def _read_frame(path: Path):
    import pandas as pd

    if not path.is_file():
        raise BrainPainterError(
            f"input file {str(path)!r} does not exist or is not a file; give the path of a CSV table."
        )
    size = path.stat().st_size
    if size == 0:
        raise BrainPainterError(
            f"input file {str(path)!r} is empty; it needs a header row and one row per image."
        )
    if size > MAX_BYTES:
        raise BrainPainterError(
            f"input file {str(path)!r} is {size / 1e6:.0f} MB; at most {MAX_BYTES // 2**20} MB is read. "
            "Split it into smaller tables."
        )
    with path.open("rb") as fh:
        head = fh.read(4096)
    if b"\x00" in head:
        raise BrainPainterError(
            f"input file {str(path)!r} is binary, not a text table; give a CSV with one column per region."
        )
    sep = "\t" if path.suffix.lower() in (".tsv", ".tab") else ","
    try:
        return pd.read_csv(path, sep=sep, encoding="utf-8-sig", dtype=str, keep_default_na=False)
    except (UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise BrainPainterError(
            f"cannot read {str(path)!r} as a CSV table ({first}); save it as UTF-8 CSV."
        ) from None


def _frame_from_mapping(data: Mapping[str, Any]):
    import pandas as pd

    values = {str(k): (list(v) if isinstance(v, list | tuple | np.ndarray) else [v]) for k, v in data.items()}
    lengths = {len(v) for v in values.values()}
    if len(lengths) > 1:
        raise BrainPainterError(
            f"the dict's values have different lengths {sorted(lengths)}; give one value per "
            "region, or equally long lists (one entry per image)."
        )
    return pd.DataFrame(values)


def _to_float(frame, columns: list[str], source: str) -> np.ndarray:
    import pandas as pd

    out = np.empty((len(frame), len(columns)), dtype=float)
    for j, col in enumerate(columns):
        series = frame[col]
        if series.dtype == object or pd.api.types.is_string_dtype(series.dtype):
            text = series.astype(str).str.strip()
            empty = text.isin(["", "nan", "NaN", "NA", "N/A", "n/a", "NULL", "null", "None"])
            numbers = pd.to_numeric(text.where(~empty, None), errors="coerce")
            bad = numbers.isna() & ~empty
        else:
            numbers = pd.to_numeric(series, errors="coerce")
            bad = numbers.isna() & series.notna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise BrainPainterError(
                f"{source}: column {col!r} row {i + 1} holds {str(series.iloc[i])!r}, which is not a number; "
                "cells must be numbers or empty (empty = no data)."
            )
        arr = numbers.to_numpy(dtype=float)
        if np.isinf(arr).any():
            i = int(np.flatnonzero(np.isinf(arr))[0])
            raise BrainPainterError(
                f"{source}: column {col!r} row {i + 1} is infinite; cells must be finite numbers or empty."
            )
        out[:, j] = arr
    return out


def read_table(
    data: Any,
    atlas: Atlas | str = "dk",
    *,
    image_column: str | None = None,
    strict: bool = False,
) -> RegionTable:
    """Read a region-value table and resolve its columns against an atlas.

    Parameters
    ----------
    data : path-like, pandas.DataFrame or dict
        A BrainPainter CSV (``Image-name-unique`` + one column per region),
        a DataFrame of the same shape, or ``{region: value or [values]}``.
    atlas : Atlas or str
    image_column : str, optional
        Column with the image names; default ``Image-name-unique`` when
        present, otherwise rows are numbered ``1, 2, ...``.
    strict : bool
        Unmatched columns are an error instead of a report entry.

    Returns
    -------
    RegionTable
    """
    import pandas as pd

    from brainpainter.atlas import get_atlas

    if isinstance(atlas, str):
        atlas = get_atlas(atlas)
    if isinstance(data, pd.DataFrame):
        frame, source = data.copy(), "DataFrame"
        frame.columns = [str(c) for c in frame.columns]
    elif isinstance(data, Mapping):
        frame, source = _frame_from_mapping(data), "dict"
    elif isinstance(data, str | Path):
        frame, source = _read_frame(Path(data)), str(data)
    else:
        raise BrainPainterError(
            f"input of type {type(data).__name__} is not supported; give a CSV path, a pandas "
            "DataFrame or a dict of region to value(s)."
        )
    frame.columns = [str(c).strip() for c in frame.columns]
    if len(frame.columns) == 0:
        raise BrainPainterError(f"{source} has no columns; it needs one column per region.")

    if image_column is None:
        lower = {c.lower(): c for c in frame.columns}
        image_column = lower.get(IMAGE_COLUMN.lower())
    elif image_column not in frame.columns:
        raise BrainPainterError(
            f"image column {image_column!r} is not in {source}; its columns start "
            f"{list(frame.columns[:5])}."
        )
    if len(frame) == 0:
        raise BrainPainterError(f"{source} has a header but no rows; add one row per image.")
    if image_column is not None:
        images = [str(v).strip() for v in frame[image_column].tolist()]
        empty = [i + 1 for i, v in enumerate(images) if not v]
        if empty:
            raise BrainPainterError(f"{source}: row {empty[0]} has an empty image name in {image_column!r}.")
    else:
        images = [str(i + 1) for i in range(len(frame))]
    dupes = sorted({n for n in images if images.count(n) > 1})
    if dupes:
        raise BrainPainterError(
            f"{source}: image names must be unique; {dupes[:3]} appear more than once."
        )

    resolver = NameResolver.for_atlas(atlas)
    columns: dict[str, str | None] = {}
    by_region: dict[str, str] = {}
    for col in frame.columns:
        if col == image_column:
            continue
        key = resolver.resolve(col)
        if key is not None and key in by_region:
            raise BrainPainterError(
                f"{source}: columns {by_region[key]!r} and {col!r} both name region {key!r}; keep one."
            )
        if col in columns:
            raise BrainPainterError(f"{source}: column {col!r} appears twice; keep one.")
        columns[col] = key
        if key is not None:
            by_region[key] = col
    unmatched = [c for c, k in columns.items() if k is None]
    if not by_region:
        sample = unmatched[:3]
        hint = resolver.suggest(sample[0]) if sample else []
        raise BrainPainterError(
            f"{source}: no column names a {atlas.name} region (columns start {sample}); "
            f"use names like {atlas.keys[:2]}" + (f"; did you mean {hint[0]!r}?" if hint else ".")
        )
    if strict and unmatched:
        sugg = resolver.suggest(unmatched[0])
        raise BrainPainterError(
            f"{source}: {len(unmatched)} column(s) match no {atlas.name} region, e.g. {unmatched[0]!r}"
            + (f" (did you mean {sugg[0]!r}?)" if sugg else "")
            + "; rename them or drop --strict."
        )
    regions = list(by_region)
    values = _to_float(frame, [by_region[k] for k in regions], source)
    return RegionTable(tuple(images), tuple(regions), values, atlas, columns, source)
