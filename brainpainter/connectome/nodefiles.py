"""Node files: where the nodes are (a coordinates table, BrainNet Viewer's ``.node``) and a vector per node.

* A coordinates table (CSV, TSV, .xlsx; read as region tables are) has a name
  column (``name``, ``label``, ``region`` or ``node``) and ``x``, ``y``, ``z``
  (millimetres); its other columns can give node values, categories or labels.
* BrainNet Viewer's ``.node`` is white-space separated, one node a line:
  ``x y z colour size label`` (``#`` starts a comment; a label ``-`` is none).
  Its columns are called ``color``, ``size`` and ``label``.
* A vector (node values, categories or labels) is a column of the nodes file,
  a file of one entry per node (text: one a line, or separated by commas or
  white space; ``.npy``), or a sequence.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, nearest
from brainpainter.io.files import read_input
from brainpainter.io.rawtable import max_bytes
from brainpainter.io.readers import decode_text
from brainpainter.table.cells import is_empty, is_text, to_number

NAME_COLUMNS = ("name", "label", "region", "node")
BRAINNET_COLUMNS = ("color", "size", "label")
ENV = "BRAINPAINTER_MAX_INPUT_MB"


@dataclass(frozen=True)
class NodeTable:
    """Nodes as a nodes file gives them.

    Attributes
    ----------
    names : tuple of str, (N,)
        Node names (a ``.node`` file's labels; ``node1``... where it has none).
    positions : ndarray, (N, 3) float64
        Coordinates as written (millimetres, in the file's space).
    columns : dict of str to list
        The other columns by name (lower case), one cell per node.
    source : str
    """

    names: tuple[str, ...]
    positions: NDArray[np.float64]
    columns: dict[str, list[Any]] = field(default_factory=dict)
    source: str = ""

    @property
    def is_brainnet(self) -> bool:
        """Whether it came from a BrainNet Viewer ``.node`` file."""
        return self.source.lower().endswith(".node")


def read_nodes(path: str | os.PathLike[str]) -> NodeTable:
    """Read a nodes file: BrainNet Viewer ``.node`` by its suffix, a coordinates table otherwise.

    Raises
    ------
    BrainPainterError
        A missing name or x/y/z column, a coordinate that is no finite number, two nodes of one name.
    """
    path = Path(path)
    table = _read_brainnet(path) if path.suffix.lower() == ".node" else _read_coordinates(path)
    seen: set[str] = set()
    for name in table.names:
        if name in seen:
            raise BrainPainterError(f"nodes file {str(path)!r} names node {name!r} twice; give each "
                                    "node once.")
        seen.add(name)
    return table


def _read_brainnet(path: Path) -> NodeTable:
    raw = read_input(path, "nodes file", max_bytes(), hint="give a BrainNet Viewer .node file", env=ENV)
    rows: list[list[str]] = []
    for number, line in enumerate(decode_text(raw, str(path)).splitlines(), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        fields = text.split()
        if not 3 <= len(fields) <= 6:
            raise BrainPainterError(
                f"nodes file {str(path)!r} line {number} has {len(fields)} fields; a BrainNet Viewer "
                ".node line is 'x y z colour size label' (at least x y z). Fix that line.")
        rows.append(fields + [""] * (6 - len(fields)))
    if not rows:
        raise BrainPainterError(f"nodes file {str(path)!r} holds no node; a .node file has one line "
                                "'x y z colour size label' per node.")
    positions = _coordinates([r[:3] for r in rows], str(path))
    labels = ["" if r[5] in ("", "-") else r[5] for r in rows]
    named = all(labels) and len(set(labels)) == len(labels)
    names = tuple(labels) if named else tuple(f"node{i + 1}" for i in range(len(rows)))
    columns = {"color": [r[3] for r in rows], "size": [r[4] for r in rows], "label": labels}
    return NodeTable(names, positions, columns, str(path))


def _read_coordinates(path: Path) -> NodeTable:
    from brainpainter.io.readers import read_raw

    table = read_raw(path)
    lower = [h.strip().lower() for h in table.header]
    missing = [c for c in "xyz" if c not in lower]
    name_col = next((lower.index(c) for c in NAME_COLUMNS if c in lower), None)
    if missing or name_col is None:
        raise BrainPainterError(
            f"nodes file {str(path)!r} has the columns {table.header[:8]}; a nodes file needs a name column "
            f"({' or '.join(NAME_COLUMNS)}) and x, y, z (or is a BrainNet Viewer .node file). Add them.")
    if not table.rows:
        raise BrainPainterError(f"nodes file {str(path)!r} has a header but no node; give one row per node.")
    positions = _coordinates([[r[lower.index(c)] for c in "xyz"] for r in table.rows], str(path),
                             table.decimal_comma)
    names = tuple(str(r[name_col]).strip() for r in table.rows)
    columns = {h: [r[i] for r in table.rows] for i, h in enumerate(lower)}
    return NodeTable(names, positions, columns, str(path))


def _coordinates(rows: list[list[Any]], source: str, decimal_comma: bool = False) -> NDArray[np.float64]:
    out = np.zeros((len(rows), 3))
    for i, row in enumerate(rows):
        for j, cell in enumerate(row):
            value = to_number(cell, decimal_comma)
            if value is None or not math.isfinite(value):
                raise BrainPainterError(
                    f"nodes file {source!r}: node {i + 1} has {'xyz'[j]} = {str(cell)[:40]!r}; "
                    "coordinates must be finite numbers (millimetres). Fix that cell.")
            out[i, j] = value
    return out


# -- vectors -------------------------------------------------------------------------------------
def node_cells(given: Any, n: int, what: str, nodes: NodeTable | None = None,
               names: Sequence[str] | None = None, key_of: Callable[[str], str | None] | None = None
               ) -> list[Any] | None:
    """One cell per node from a column of `nodes`, a vector file or a sequence; None when not given.

    Parameters
    ----------
    given : str, path-like, sequence or None
        A column name of `nodes` (case-insensitive), a file, or the cells. A text file of one entry
        per line is in the matrix's order; one of ``name,entry`` lines (a header line allowed) is
        matched to the nodes by name (nodes it lacks get an empty cell).
    n : int
        Number of nodes.
    what : str
        ``"node values"``, ``"node categories"``, ``"node labels"``, for messages.
    nodes : NodeTable, optional
    names : sequence of str, (N,), optional
        The nodes' names, for a file of ``name,entry`` lines.
    key_of : callable, optional
        The node name another spelling means (an atlas's region names), or None.

    Raises
    ------
    BrainPainterError
        Not a column nor a file, another count than `n`, or names that are no node.
    """
    if given is None:
        return None
    if isinstance(given, str | os.PathLike):
        text = str(given)
        if nodes is not None and text.strip().lower() in nodes.columns:
            return list(nodes.columns[text.strip().lower()])
        path = Path(text)
        if not path.is_file() and nodes is not None:
            raise BrainPainterError(
                f"{what} {text!r} is neither a column of {nodes.source!r} (it has "
                f"{sorted(nodes.columns)}) nor a file; give a column name or a file of one entry per node.")
        source = text
        rows = _vector_file(path, what, n)
        named = None
        if names is not None and rows and all(len(r) == 2 and is_text(r[0]) for r in rows):
            named = _by_name(rows, names, key_of, what, source)
        if named is not None:
            return named
        cells = [c for r in rows for c in r]
    else:
        source = f"the {what} given"
        cells = list(np.asarray(given, dtype=object).ravel()) if not isinstance(given, list) else list(given)
    if len(cells) != n:
        raise BrainPainterError(
            f"{what} {source!r} has {len(cells)} entries but the connectome has {n} nodes; give one "
            "entry per node, in the matrix's order (or name,entry lines).")
    return cells


def _by_name(rows: list[list[str]], names: Sequence[str], key_of: Callable[[str], str | None] | None,
             what: str, source: str) -> list[Any] | None:
    """Cells of ``name,entry`` rows in the nodes' order (a first row of column names is a header); None
    when no row names a node (``visual,motor``: two entries on one line)."""
    where = {name.lower(): i for i, name in enumerate(names)}

    def node(text: str) -> int | None:
        hit = where.get(text.strip().lower())
        if hit is None and key_of is not None:
            key = key_of(text)
            hit = None if key is None else where.get(key.lower())
        return hit

    if all(node(r[0]) is None for r in rows):
        return None
    first, rest = rows[0], rows[1:]
    if node(first[0]) is None and (first[0].strip().lower() in (*NAME_COLUMNS, "roi", "parcel") or (
            rest and is_text(first[1]) and not any(is_text(r[1]) for r in rest))):
        rows = rest  # a header: "region,strength"
    cells: list[Any] = [""] * len(names)
    seen: dict[int, str] = {}
    for name, cell in rows:
        i = node(name)
        if i is None:
            close = nearest(name, names)
            raise BrainPainterError(
                f"{what} {source!r} names {name!r}, which is no node of the connectome"
                + (f" (did you mean {close[0]!r}?)" if close else "") + "; give the nodes' names.")
        if i in seen:
            raise BrainPainterError(f"{what} {source!r} names node {names[i]!r} twice ({seen[i]!r} and "
                                    f"{name!r}); give each node once.")
        seen[i] = name
        cells[i] = cell
    return cells


def _vector_file(path: Path, what: str, n: int) -> list[list[Any]]:
    """The entries of a vector file, line by line; more than two per node is refused before splitting."""
    if path.suffix.lower() == ".npy":
        from brainpainter.connectome.matrix import read_npy

        return [[v] for v in read_npy(path, what, ndim=1)]
    raw = read_input(path, what, max_bytes(), hint="give a file of one entry per node", env=ENV)
    rows: list[list[Any]] = []
    most, count = 2 * n + 2, 0  # name,entry lines and a header
    for line in decode_text(raw, str(path)).splitlines():
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        sep = "," if "," in text else "\t" if "\t" in text else None
        count += (text.count(sep) if sep else text.count(" ")) + 1
        if count > most:
            raise BrainPainterError(
                f"{what} {str(path)!r} has more than {most} entries but the connectome has {n} nodes; give "
                "one entry per node, in the matrix's order (or name,entry lines).")
        rows.append([c.strip() for c in text.split(sep)])
    return rows


def node_values(cells: Sequence[Any], source: str) -> NDArray[np.float64]:
    """Cells as one number per node (NaN where empty).

    Raises
    ------
    BrainPainterError
        A cell that is no finite number nor empty.
    """
    out = np.full(len(cells), np.nan)
    for i, cell in enumerate(cells):
        value = to_number(cell, decimal_comma=False)
        if value is None or math.isinf(value):
            raise BrainPainterError(
                f"node values {source!r}: node {i + 1} has {str(cell)[:40]!r}, not a number; node values are "
                "numbers (empty for none). Fix that entry or give another column.")
        out[i] = value
    return out


def node_texts(cells: Sequence[Any], numbers: bool = False) -> tuple[str, ...]:
    """Cells as one text per node (empty and ``-`` as ``""``).

    Parameters
    ----------
    cells : sequence, (N,)
    numbers : bool
        Write whole numbers as integers (``1.0`` and ``1`` both ``"1"``: module numbers as categories).
    """
    out = []
    for cell in cells:
        if is_empty(cell) or str(cell).strip() == "-":
            out.append("")
            continue
        value = to_number(cell) if numbers else None
        if value is not None and math.isfinite(value) and value == int(value):
            out.append(str(int(value)))
        else:
            out.append(str(cell).strip())
    return tuple(out)
