"""Connectivity matrix files: one square array of weights and the node names the file gives.

One loader per format, the format's library reading it:

* text (``.csv``, ``.tsv``, ``.txt``, BrainNet Viewer's ``.edge``; any separator the table
  reader sniffs): with or without a header row of names and a first column of names;
* ``.npy`` (numpy's header reader; never unpickled): the data taken from the bytes read;
* ``.mat`` (``scipy.io.loadmat``, once :mod:`brainpainter.connectome.matfile` checked the variable):
  the one 2-D numeric variable (or the one square one);
* CIFTI-2 ``.pconn.nii`` (nibabel): node names from its parcel axes.

Every file is bounded before it is read: text by its size (``BRAINPAINTER_MAX_INPUT_MB``), a
binary matrix by the shape its header declares (the weights must fit the same limit as float64,
and an uncompressed file must hold the bytes it declares), so a hostile header never allocates.
"""

from __future__ import annotations

import contextlib
import csv
import logging
import math
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.files import check_input, read_input
from brainpainter.io.rawtable import max_bytes
from brainpainter.table.cells import is_text, to_number

#: What ``--connectome`` reads, for messages.
FORMATS = "a CSV/TSV/text matrix, .edge, .npy, .mat or CIFTI .pconn.nii"
WHAT = "connectome matrix"
ENV = "BRAINPAINTER_MAX_INPUT_MB"
#: What a matrix of another shape is told.
SQUARE = ("a connectivity matrix is square (N x N): its rows and columns must be the same nodes in the same "
          "order. Give the whole N x N matrix (names, if any, in the first row and column).")


@dataclass(frozen=True)
class Matrix:
    """A connectivity matrix as read.

    Attributes
    ----------
    weights : ndarray, (N, N) float64
        The values as given (0, no edge, where a cell was empty; NaN where it said NaN).
    names : tuple of str, (N,), or None
        Node names the file gives (a header, a first column, CIFTI parcels); None when it gives none.
    source : str
        Where it came from, for messages.
    """

    weights: NDArray[np.float64]
    names: tuple[str, ...] | None
    source: str


def read_matrix(matrix: Any) -> Matrix:
    """Read a connectivity matrix from a file or an array.

    Parameters
    ----------
    matrix : path-like, array-like (N, N), pandas DataFrame or Matrix
        A file (see the module docstring) or the weights themselves; a DataFrame's string columns
        are the node names. A :class:`Matrix` (already read) is returned as it is.

    Returns
    -------
    Matrix

    Raises
    ------
    BrainPainterError
        An unreadable, empty, non-square or too large matrix, or cells that are not numbers.
    """
    if isinstance(matrix, Matrix):
        return matrix
    if isinstance(matrix, str | os.PathLike):
        path = Path(matrix)
        name = path.name.lower()
        if name.endswith(".npy"):
            weights, names = read_npy(path, WHAT), None
        elif name.endswith(".mat"):
            weights, names = read_mat(path), None
        elif name.endswith((".pconn.nii", ".nii")):
            weights, names = _read_pconn(path)
        else:
            weights, names = _read_text(path)
        return checked(weights, names, str(path))
    return _from_array(matrix)


def _from_array(matrix: Any) -> Matrix:
    names: tuple[str, ...] | None = None
    if type(matrix).__module__.startswith("pandas") and hasattr(matrix, "columns"):
        columns = [str(c) for c in matrix.columns]
        if any(to_number(c) is None for c in columns):
            names = tuple(columns)
    try:
        weights = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise BrainPainterError(f"the connectome matrix given ({type(matrix).__name__}) is not numbers "
                                f"({_said(exc)}); give an (N, N) array of weights or {FORMATS} "
                                "file.") from None
    return checked(weights, names, f"the {type(matrix).__name__} given")


def _said(exc: BaseException) -> str:
    """A library's exception as a short part of one line."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:160]}"


def checked(weights: NDArray[Any], names: tuple[str, ...] | None, source: str) -> Matrix:
    """`weights` as a :class:`Matrix` once it is a non-empty, square, finite-or-NaN 2-D array.

    Parameters
    ----------
    weights : ndarray, (N, N)
    names : tuple of str, (N,), or None
    source : str
    """
    if weights.ndim != 2 or weights.size == 0 or weights.shape[0] != weights.shape[1]:
        shape = " x ".join(str(s) for s in weights.shape) or "a single number"
        what = "is empty" if weights.size == 0 else f"is {shape}"
        raise BrainPainterError(f"connectome matrix {source!r} {what}; {SQUARE}")
    if np.isinf(weights).any():
        i, j = (int(k) for k in np.argwhere(np.isinf(weights))[0])
        raise BrainPainterError(
            f"connectome matrix {source!r} has an infinite weight at row {i + 1}, column {j + 1}; weights "
            "must be finite numbers (empty or NaN for no edge). Fix or empty that cell.")
    if names is not None and len(names) != weights.shape[0]:
        raise BrainPainterError(
            f"connectome matrix {source!r} names {len(names)} nodes but has {weights.shape[0]} rows; give "
            "one name per row and column.")
    return Matrix(weights.astype(np.float64, copy=False), names, source)


# -- text ------------------------------------------------------------------------------------
def _read_text(path: Path) -> tuple[NDArray[np.float64], tuple[str, ...] | None]:
    """Weights and names of a text matrix (or a workbook); names from a header row and/or a first column.

    A text file is parsed line by line, each line's numbers at once into floats, so a matrix takes 8
    bytes a cell however it is written (not a Python string per cell).
    """
    from brainpainter.io.readers import decode_text, parse_bytes, sniff_separator

    source = str(path)
    raw = read_input(path, WHAT, max_bytes(), hint=f"give {FORMATS}", env=ENV)
    if not raw.strip():
        raise BrainPainterError(f"connectome matrix {source!r} is empty; give an N x N matrix of weights "
                                "(names, if any, in the first row and column).")
    if raw.startswith(b"PK\x03\x04"):  # a workbook: the table reader's cells (it bounds their count)
        table = parse_bytes(raw, source, path.suffix.lower())
        head: list[Any] = list(table.header)
        rows = _Rows([(i + 2, row) for i, row in enumerate(table.rows)])
        return _grid(head, 1, rows, table.decimal_comma, source)
    text = decode_text(raw, source)
    del raw
    numbered = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]  # CR LF, CR
    del text
    sep = sniff_separator(numbered[0][1][:65536], path.suffix.lower())  # a long line's start tells
    _refuse_long_lines(numbered, sep, source)
    rows = _Rows(list(numbered[1:]), sep)
    return _grid(_fields(numbered[0][1], sep), numbered[0][0], rows, sep != ",", source)


def _refuse_long_lines(numbered: list[tuple[int, str]], sep: str, source: str) -> None:
    """Refuse a line with more fields than a square matrix of these lines has, before it is split.

    Splitting a line makes a string per field; a line of millions of separators would take 50 times
    its size. Fields are counted from the separators (white space: an upper bound), not split.
    """
    most = len(numbered) + 2  # N rows + a header line; N columns + a name column + a trailing separator
    for number, line in numbered:
        fields = (line.count(" ") + line.count("\t") if sep == " " else line.count(sep)) + 1
        if fields > most and (sep != " " or len(line.split(maxsplit=most)) > most):
            raise BrainPainterError(f"connectome matrix {source!r} line {number} has more than {most} fields "
                                    f"but the file has {len(numbered)} lines; {SQUARE}")


class _Rows:
    """Rows of a matrix file, each split into cells when it is read (a text line's strings live only then).

    Parameters
    ----------
    items : list of (int, str or list)
        Each row's line number and its text line (split at `sep`) or its cells.
    sep : str
        Separator of the text lines (``" "``: white space).
    """

    def __init__(self, items: list[tuple[int, Any]], sep: str = ",") -> None:
        self.items, self.sep = items, sep

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, i: int) -> list[Any]:
        item = self.items[i][1]
        return _fields(item, self.sep) if isinstance(item, str) else list(item)

    def line(self, i: int) -> int:
        """File line of row `i`."""
        return int(self.items[i][0])


def _fields(line: str, sep: str) -> list[str]:
    """The fields of one line (quoted ones as csv reads them)."""
    if sep == " ":
        fields = line.split()
    elif '"' in line:
        try:
            fields = next(csv.reader([line], delimiter=sep, strict=True))
        except csv.Error:
            fields = line.split(sep)
    else:
        fields = line.split(sep)
    return [f.strip() for f in fields]


def _trimmed(cells: list[Any]) -> list[Any]:
    """`cells` without the empty cells at the end (trailing separators of spreadsheet exports)."""
    end = len(cells)
    while end > 1 and not str(cells[end - 1]).strip():
        end -= 1
    return cells[:end]


def _grid(head: list[Any], head_line: int, rows: _Rows, decimal_comma: bool,
          source: str) -> tuple[NDArray[np.float64], tuple[str, ...] | None]:
    """Weights and names from the first row's cells (a header or a row of weights) and the other rows."""
    named_columns = any(is_text(c) for c in head[1:]) or (len(head) == 1 and is_text(head[0]))
    if named_columns:
        head = _trimmed(head)
    else:  # the first line is a row of the matrix
        rows = _Rows([(head_line, head), *rows.items], rows.sep)
    n_rows = len(rows)
    if n_rows == 0:
        raise BrainPainterError(f"connectome matrix {source!r} has names but no rows of weights; give an "
                                "N x N matrix of weights (names, if any, in the first row and column).")
    first = rows[0]
    names_first = int(is_text(first[0]))
    if len(first) - names_first != n_rows and len(_trimmed(first)) - names_first == n_rows:
        first = _trimmed(first)  # every line ends in a separator
    width = len(first)
    if n_rows != width - names_first:  # refused before any row is parsed
        raise BrainPainterError(f"connectome matrix {source!r} is {n_rows} x {width - names_first}; {SQUARE}")
    firsts: list[Any] = []
    rest = np.empty((n_rows, width - 1))
    for i in range(n_rows):
        cells = rows[i] if i else first
        if len(cells) > width and not any(str(c).strip() for c in cells[width:]):
            cells = cells[:width]
        if len(cells) != width:
            raise BrainPainterError(
                f"connectome matrix {source!r} line {rows.line(i)} has {len(cells)} fields but line "
                f"{rows.line(0)} has {width}; every row needs one cell per column (check separators and "
                "quotes).")
        firsts.append(cells[0])
        rest[i] = _numbers(cells[1:], decimal_comma, source, rows.line(i), 2)
    named_rows = all(is_text(c) for c in firsts)
    if named_rows:
        weights = rest
    else:
        column = np.concatenate([_numbers([c], decimal_comma, source, rows.line(i), 1)
                                 for i, c in enumerate(firsts)])
        weights = np.column_stack([column, rest])
        if not named_columns and _numbered_index(str(head[0]), weights):
            weights = weights[1:, 1:]  # pandas' to_csv of an unnamed matrix: a header and a column of 0..N-1
    row_names = [str(c).strip() for c in firsts] if named_rows else None
    column_names = None
    if named_columns:
        header = [str(c).strip() for c in head]
        column_names = header[1:] if len(header) == weights.shape[1] + 1 else header
    if row_names is not None and column_names is not None and row_names != column_names:
        k = next((i for i, (a, b) in enumerate(zip(row_names, column_names, strict=False)) if a != b),
                 min(len(row_names), len(column_names)))
        raise BrainPainterError(
            f"connectome matrix {source!r}: its row names and column names differ (row {k + 1} is "
            f"{_at(row_names, k)!r}, column {k + 1} is {_at(column_names, k)!r}); rows and columns must be "
            "the same nodes in the same order.")
    names = row_names if row_names is not None else column_names
    return weights, None if names is None else tuple(names)


def _numbered_index(corner: str, weights: NDArray[np.float64]) -> bool:
    """Whether the first row and column are an empty corner and the counts 0..N-1 (or 1..N)."""
    if corner.strip() or weights.shape[0] != weights.shape[1] or len(weights) < 2:
        return False
    head, first = weights[0, 1:], weights[1:, 0]
    count = np.arange(len(head), dtype=float)
    counts = np.array_equal(head, count) or np.array_equal(head, count + 1)
    return bool(counts and np.array_equal(head, first))


def _at(names: list[str], k: int) -> str:
    return names[k] if k < len(names) else "(none)"


def _numbers(cells: list[Any], decimal_comma: bool, source: str, line: int, col0: int) -> NDArray[np.float64]:
    """One row's cells as floats (an empty cell is 0: no edge, not a NaN dropped with a warning); a cell
    that is no number is an error."""
    try:
        return np.array(cells, dtype=np.float64)  # the common case: every cell a plain number
    except ValueError:
        pass
    out = np.full(len(cells), np.nan)
    for j, cell in enumerate(cells):
        value = 0.0 if cell is None or not str(cell).strip() else to_number(cell, decimal_comma)
        if value is None:
            raise BrainPainterError(
                f"connectome matrix {source!r}: line {line}, column {j + col0} is {str(cell)[:40]!r}, not a "
                "number; a matrix holds numbers (empty or NaN for no edge), with names only in its first row "
                "and column.")
        out[j] = value
    return out


# -- binary ------------------------------------------------------------------------------------
def limit_error(path: Path, shape: tuple[int, ...], limit: int, what: str = WHAT) -> BrainPainterError:
    need = math.prod(shape) * 8
    return BrainPainterError(
        f"{what} {str(path)!r} declares a {' x '.join(map(str, shape))} array ({need / 2**20:.0f} "
        f"MB as float64); at most {limit / 2**20:.0f} MB is read, to keep memory bounded. Check that it is "
        f"the right file, or raise the limit with {ENV}.")


def read_npy(path: Path, what: str, ndim: int = 2) -> NDArray[np.float64]:
    """A ``.npy`` array of numbers, its header's shape and dtype checked against the limit and the file's
    size before anything is read.

    Parameters
    ----------
    path : Path
    what : str
        What the file is, for messages (``"connectome matrix"``, ``"node values"``).
    ndim : int
        Dimensions it must have.

    Returns
    -------
    ndarray, float64
    """
    import io

    limit = max_bytes()
    raw = read_input(path, what, limit, hint=f"give a .npy file of {ndim} dimension(s)", env=ENV)
    fmt: Any = np.lib.format  # numpy's header readers are untyped
    try:
        with warnings.catch_warnings():  # numpy warns on odd headers (Python 2's)
            warnings.simplefilter("ignore")
            fh = io.BytesIO(raw)
            version = fmt.read_magic(fh)
            reader = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
            shape, fortran, dtype = reader(fh)
            offset = fh.tell()
    except Exception as exc:  # numpy raises ValueError, SyntaxError, TokenError... for a broken header
        raise BrainPainterError(f"{what} {str(path)!r} is not a readable .npy file ({_said(exc)}); save "
                                "the matrix with numpy.save.") from None
    if dtype.hasobject or dtype.kind not in "biuf":
        raise BrainPainterError(f"{what} {str(path)!r} holds {dtype} values; a matrix holds numbers "
                                "(save a float array with numpy.save).")
    if math.prod(shape) * 8 > limit:
        raise limit_error(path, tuple(shape), limit, what)
    if len(shape) != ndim:
        raise BrainPainterError(f"{what} {str(path)!r} holds a {len(shape)}-D array of shape "
                                f"{tuple(shape)}; it must have {ndim} dimension(s). Save the right array "
                                "with numpy.save.")
    if math.prod(shape) * dtype.itemsize > len(raw) - offset:
        raise BrainPainterError(
            f"{what} {str(path)!r} declares a {' x '.join(map(str, shape))} {dtype} array but holds "
            f"only {len(raw) - offset} bytes of data; the file is cut short or broken. Save it again with "
            "numpy.save.")
    data = np.frombuffer(raw, dtype=dtype, count=math.prod(shape), offset=offset)
    return data.reshape(shape, order="F" if fortran else "C").astype(np.float64)


_MAT_NUMERIC = ("double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                "logical")


def read_mat(path: Path, ndim: int = 2) -> NDArray[np.float64]:
    """The one numeric variable of `ndim` dimensions of a MATLAB file (or its one whose first two are equal:
    N x N, a series' N x N x T), its size and elements checked (:mod:`brainpainter.connectome.matfile`)
    before scipy reads it."""
    import io

    import scipy.io

    from brainpainter.connectome.matfile import check_variable

    limit = max_bytes()
    raw = read_input(path, WHAT, limit, hint=f"give {FORMATS}", env=ENV)
    try:
        variables = scipy.io.whosmat(io.BytesIO(raw))
    except NotImplementedError:  # scipy: "Please use HDF reader for matlab v7.3 files"
        raise BrainPainterError(
            f"connectome matrix {str(path)!r} is a MATLAB v7.3 (HDF5) file, which is not read; save it with "
            "save(FILE, 'W', '-v7'), or as CSV.") from None
    except Exception as exc:  # scipy raises many types for a broken file
        raise BrainPainterError(f"connectome matrix {str(path)!r} is not a readable MATLAB .mat file "
                                f"({_said(exc)}); save it again with MATLAB's save.") from None
    # MATLAB keeps every number 2-D: a scalar is 1 x 1, a vector 1 x n
    matrices = [(n, tuple(s)) for n, s, cls in variables
                if len(s) == ndim and min(s) > 1 and cls in _MAT_NUMERIC]
    square = [(n, s) for n, s in matrices if s[0] == s[1]]
    pick = matrices if len(matrices) == 1 else square if len(square) == 1 else []
    if not pick:
        shown = ", ".join(f"{n} ({' x '.join(map(str, s))} {cls})" for n, s, cls in variables) or "nothing"
        raise BrainPainterError(
            f"connectome matrix {str(path)!r} holds {shown}; it needs exactly one {ndim}-D numeric (square) "
            "variable. Save the matrix alone (save(FILE, 'W')) or as CSV.")
    name, shape = pick[0]
    if math.prod(shape) * 8 > limit:
        raise limit_error(path, shape, limit)
    if raw[126:128] in (b"IM", b"MI") and raw[124:126] != b"\x00\x00":  # v5 (a v4 file has no such header)
        check_variable(raw, name, limit, str(path))
    try:
        with warnings.catch_warnings():  # scipy warns and returns a text for an unreadable variable
            warnings.simplefilter("ignore")
            array = scipy.io.loadmat(io.BytesIO(raw), variable_names=[name]).get(name)
    except Exception as exc:
        raise BrainPainterError(f"connectome matrix {str(path)!r}: variable {name!r} could not be read "
                                f"({_said(exc)}); save it again with MATLAB's save.") from None
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "biuf" or array.shape != shape:
        raise BrainPainterError(f"connectome matrix {str(path)!r}: variable {name!r} could not be read as "
                                f"the {' x '.join(map(str, shape))} numbers its header declares; the file is "
                                "damaged. Save it again with MATLAB's save.")
    return np.asarray(array, dtype=np.float64)


@contextlib.contextmanager
def _quiet_nibabel() -> Iterator[None]:
    """nibabel's warnings and log lines about a damaged header kept out (the error line says what is
    wrong)."""
    logger = logging.getLogger("nibabel")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        logger.setLevel(level)


def _read_pconn(path: Path) -> tuple[NDArray[np.float64], tuple[str, ...]]:
    """A CIFTI-2 parcel-by-parcel matrix and its parcel names (checked to be the same on both axes)."""
    import nibabel as nib

    limit = max_bytes()
    size = check_input(path, WHAT, limit, hint=f"give {FORMATS}").stat().st_size
    with _quiet_nibabel():
        try:
            img: Any = nib.load(str(path), mmap=False)
            axes = [img.header.get_axis(i) for i in range(2)]
            stored = tuple(int(s) for s in img.dataobj.shape)
        except Exception as exc:  # nibabel raises many types for a broken header
            raise BrainPainterError(f"connectome matrix {str(path)!r} is not a readable CIFTI-2 file "
                                    f"({_said(exc)}); give a .pconn.nii (or {FORMATS}).") from None
        if not all(isinstance(a, nib.cifti2.cifti2_axes.ParcelsAxis) for a in axes):
            kinds = [type(a).__name__ for a in axes]
            raise BrainPainterError(
                f"connectome matrix {str(path)!r} is a CIFTI-2 file with axes {kinds}; a connectome is a "
                ".pconn.nii (parcels by parcels). Give a parcellated connectivity file (wb_command "
                "-cifti-parcellate).")
        shape = (len(axes[0]), len(axes[1]))
        if math.prod(shape) * 8 > limit:
            raise limit_error(path, shape, limit)
        if stored != shape or math.prod(shape) * img.get_data_dtype().itemsize > size:
            raise BrainPainterError(
                f"connectome matrix {str(path)!r} names {shape[0]} x {shape[1]} parcels but its data are "
                f"{' x '.join(map(str, stored))} (of a {size}-byte file); it is damaged or cut short. Save "
                "it again.")
        rows, columns = (tuple(str(n) for n in a.name) for a in axes)
        if rows != columns:
            raise BrainPainterError(f"connectome matrix {str(path)!r}: its two parcel axes name different "
                                    "parcels; a connectome has the same parcels as rows and columns.")
        try:
            weights = np.asarray(img.dataobj, dtype=np.float64)
        except Exception as exc:
            raise BrainPainterError(f"connectome matrix {str(path)!r}: the data could not be read "
                                    f"({_said(exc)}); save it again.") from None
    return weights, rows
