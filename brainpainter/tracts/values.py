"""Values on bundles: one value per bundle, or along-tract profiles of N nodes per bundle.

Layouts (read by :func:`brainpainter.io.readers.read_raw`, so CSV, TSV,
``;``-separated with decimal commas, .xlsx and DataFrames all work):

* **per bundle, wide**: columns are bundle names (``AF_left``, ``ARC_L``,
  ``Left Arcuate``, ...: :func:`brainpainter.tracts.names.canonical`), rows are
  images, with an optional image column (``image``, ``subject``,
  ``subjectID``, ``Image-name-unique``);
* **per bundle, long**: a bundle column (``bundle``, ``tract``, ``tractID``), one value
  column and an optional image column: a row per bundle (and image);
* **profile, long**: a ``node`` (or ``nodeID``) column, a bundle column
  (``bundle``, ``tract``, ``tractID``), one value column (pyAFQ's
  ``tract_profiles.csv`` has several: name one with `value`) and an optional
  image column;
* **profile, wide**: a ``node`` column and one column per bundle (TractSeg's
  ``Tractometry.csv`` with a ``node`` column added).

Rows without an image column (or a single image) colour every image.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.tracts.names import bundle_key, canonical

#: Palette key of the bundles drawn without a value where other bundles have values (issue 44): the tract
#: scale's missing colour, as regions without values (not direction colours beside a value bar).
MISSING_TRACT_KEY = "tract-missing"
NODE_COLUMNS = ("node", "nodeid", "node_id", "nodes")
BUNDLE_COLUMNS = ("bundle", "tract", "tractid", "tract_id", "bundle_name", "tractname")
IMAGE_COLUMNS = ("image-name-unique", "image", "subject", "subjectid", "subject_id", "participant_id",
                 "sub", "id")
#: Columns of a long profile that are no measure: pandas' unnamed index, pyAFQ's session.
NOT_MEASURES = ("", "unnamed: 0", "index", "sessionid", "session_id", "session", "ses")
#: Nodes per bundle at most (a palette slot each).
MAX_NODES = 1000


@dataclass(frozen=True)
class TractValues:
    """Values per image on bundles or on bundles' nodes.

    Attributes
    ----------
    images : tuple of str, or None
        Image names of the rows; None: one row for every image.
    keys : tuple of str
        Palette keys: ``tract:AF_left`` (one value per bundle) or
        ``tract:AF_left:17`` (node 17 of a profile).
    values : ndarray of float, shape (n_rows, n_keys)
        NaN where a cell is empty.
    nodes : tuple of (str, int)
        Bundle -> 1 or its number of nodes (the scene's ``tract_nodes``).
    """

    images: tuple[str, ...] | None
    keys: tuple[str, ...]
    values: NDArray[Any]
    nodes: tuple[tuple[str, int], ...]

    def row(self, image: str) -> dict[str, float]:
        """Values of `image` by palette key (all NaN for an image the table lacks; a table of one row
        colours every image, whatever its row is named)."""
        if self.images is None or len(self.images) == 1:
            i: int | None = 0
        else:
            i = self.images.index(image) if image in self.images else None
        vals = self.values[i] if i is not None else np.full(len(self.keys), np.nan)
        return dict(zip(self.keys, vals.tolist(), strict=True))

    @property
    def bundles(self) -> tuple[str, ...]:
        return tuple(n for n, _ in self.nodes)

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary: bundles with their nodes, the finite value range (None: no value)."""
        finite = self.values[np.isfinite(self.values)]
        return {"bundles": {name: n for name, n in self.nodes},
                "value_range": [float(finite.min()), float(finite.max())] if finite.size else None}


def _number(cell: Any, decimal_comma: bool) -> float:
    if cell is None:
        return math.nan
    if isinstance(cell, int | float):
        return float(cell)
    text = str(cell).strip()
    if decimal_comma:
        text = text.replace(",", ".")
    if text.lower() in ("", "nan", "na", "n/a"):
        return math.nan
    try:
        return float(text)
    except ValueError:
        return math.nan


def _find(header: list[str], names: tuple[str, ...]) -> int | None:
    low = [h.strip().lower() for h in header]
    for name in names:
        if name in low:
            return low.index(name)
    return None


def is_long(data: Any) -> bool:
    """Whether `data` (anything :func:`read_tract_values` reads) is a long table of tract values.

    A long table has a bundle column (``bundle``/``tractID``): a row per bundle, or per node of a
    bundle (pyAFQ's ``tract_profiles.csv``). It holds tract values only, whatever else it holds.
    """
    from brainpainter.io.readers import read_raw

    return _find(list(read_raw(data).header), BUNDLE_COLUMNS) is not None


def read_tract_values(data: Any, value: str | None = None) -> TractValues:
    """Read a table of bundle values or along-tract profiles (layouts in the module docstring).

    Parameters
    ----------
    data : path, DataFrame, dict, ...
        Anything :func:`brainpainter.io.readers.read_raw` reads.
    value : str, optional
        Long profiles: the value column, where there are several numeric columns.

    Returns
    -------
    TractValues

    Raises
    ------
    BrainPainterError
        No bundle column or value column, a node that is not a whole number, or too many nodes.
    """
    from brainpainter.io.readers import read_raw

    raw = read_raw(data)
    header, rows, dc = list(raw.header), raw.rows, raw.decimal_comma
    image_col = _find(header, IMAGE_COLUMNS)
    if image_col is None and raw.index_column is not None and raw.index_column in header:
        image_col = header.index(raw.index_column)
    node_col = _find(header, NODE_COLUMNS)
    bundle_col = _find(header, BUNDLE_COLUMNS)
    if bundle_col is not None:  # long: a row per bundle (and node, and image)
        return _long_profile(raw.source, header, rows, dc, image_col, node_col, bundle_col, value)
    skip = {c for c in (image_col, node_col) if c is not None}
    cols = [j for j in range(len(header)) if j not in skip and header[j].strip()]
    if not cols:
        raise BrainPainterError(f"tract values {raw.source!r} have no bundle column; give columns named "
                                "after bundles (AF_left, CST_right, ...) or a long table "
                                "with bundle,node,value.")
    names = [canonical(header[j]) for j in cols]
    matrix = np.array([[_number(r[j], dc) for j in cols] for r in rows], dtype=float).reshape(len(rows), -1)
    if node_col is not None:  # wide profile: rows are nodes
        node = _nodes(raw.source, [r[node_col] for r in rows], dc)
        n = int(node.max()) + 1
        vals = np.full((1, len(names) * n), np.nan)
        for b in range(len(names)):
            vals[0, b * n + node] = matrix[:, b]
        keys = tuple(bundle_key(name, k) for name in names for k in range(n))
        return TractValues(None, keys, vals, tuple((name, n) for name in names))
    images = None if image_col is None else tuple(str(r[image_col]).strip() for r in rows)
    if images is None and len(rows) > 1:
        images = tuple(str(i + 1) for i in range(len(rows)))
    return TractValues(images, tuple(bundle_key(n) for n in names), matrix, tuple((n, 1) for n in names))


def _nodes(source: str, cells: list[Any], dc: bool) -> NDArray[Any]:
    node = np.array([_number(c, dc) for c in cells])
    if not len(node) or np.any(~np.isfinite(node)) or np.any(node != np.round(node)) or node.min() < 0:
        raise BrainPainterError(f"the node column of {source!r} must hold whole numbers 0, 1, ...; give the "
                                "node index of each row (pyAFQ's nodeID, 0-99).")
    if node.max() >= MAX_NODES:
        raise BrainPainterError(f"{source!r} has nodes up to {int(node.max())}; at most {MAX_NODES} nodes "
                                "per bundle are drawn; resample the profiles to fewer nodes (100 is usual).")
    return node.astype(np.int64)


def _long_profile(source: str, header: list[str], rows: list[list[Any]], dc: bool, image_col: int | None,
                  node_col: int | None, bundle_col: int, value: str | None) -> TractValues:
    """A long table: a row per bundle, node (without a node column: one value per bundle) and image."""
    skip = {c for c in (image_col, node_col, bundle_col) if c is not None}
    if value is not None:
        if value not in header:
            raise BrainPainterError(f"value column {value!r} is not in {source!r}; its columns are {header}.")
        value_col = header.index(value)
    else:
        numeric = [j for j in range(len(header)) if j not in skip
                   and header[j].strip().lower() not in NOT_MEASURES
                   and any(math.isfinite(_number(r[j], dc)) for r in rows[:50])]
        if len(numeric) != 1:
            raise BrainPainterError(
                f"the {'profile' if node_col is not None else 'bundle'} table {source!r} has {len(numeric)} "
                f"value columns "
                f"{[header[j] for j in numeric]}; name the one to draw (--tract-value COLUMN).")
        value_col = numeric[0]
    node = (_nodes(source, [r[node_col] for r in rows], dc) if node_col is not None
            else np.zeros(len(rows), dtype=np.int64))
    n = int(node.max()) + 1 if len(node) else 1
    names = [canonical(str(r[bundle_col])) for r in rows]
    bundles = list(dict.fromkeys(names))
    images_all = [str(r[image_col]).strip() for r in rows] if image_col is not None else [""] * len(rows)
    if node_col is None and len(set(zip(names, images_all, strict=True))) < len(rows):
        raise BrainPainterError(f"the bundle table {source!r} names a bundle twice for one image; give one "
                                "row per bundle (and image), or a node column for along-tract profiles.")
    images = list(dict.fromkeys(images_all))
    keys = tuple(bundle_key(b, k if node_col is not None else None) for b in bundles for k in range(n))
    col_of: Mapping[str, int] = {b: i * n for i, b in enumerate(bundles)}
    row_of = {im: i for i, im in enumerate(images)}
    vals = np.full((len(images), len(keys)), np.nan)
    for r, name, im, k in zip(rows, names, images_all, node.tolist(), strict=True):
        vals[row_of[im], col_of[name] + k] = _number(r[value_col], dc)
    return TractValues(None if image_col is None else tuple(images), keys, vals,
                       tuple((b, n) for b in bundles))
