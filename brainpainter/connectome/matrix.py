"""Connectivity matrix files: one square array of weights and the node names the file gives.

One loader per format, the format's library reading it:

* text (``.csv``, ``.tsv``, ``.txt``, BrainNet Viewer's ``.edge``; any separator the table
  reader sniffs): with or without a header row of names and a first column of names;
* ``.npy`` (``numpy.load(allow_pickle=False)``);
* ``.mat`` (``scipy.io.loadmat``): the one 2-D numeric variable (or the one square one);
* CIFTI-2 ``.pconn.nii`` (nibabel): node names from its parcel axes.

Every file is bounded before it is read: text by its size (``BRAINPAINTER_MAX_INPUT_MB``), a
binary matrix by the shape its header declares (the weights must fit the same limit as float64,
and an uncompressed file must hold the bytes it declares), so a hostile header never allocates.
"""

from __future__ import annotations

import math
import os
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


@dataclass(frozen=True)
class Matrix:
    """A connectivity matrix as read.

    Attributes
    ----------
    weights : ndarray, (N, N) float64
        The values as given (NaN where a cell was empty).
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
    matrix : path-like, array-like (N, N) or pandas DataFrame
        A file (see the module docstring) or the weights themselves; a DataFrame's string columns
        are the node names.

    Returns
    -------
    Matrix

    Raises
    ------
    BrainPainterError
        An unreadable, empty, non-square or too large matrix, or cells that are not numbers.
    """
    if isinstance(matrix, str | os.PathLike):
        path = Path(matrix)
        name = path.name.lower()
        if name.endswith(".npy"):
            weights, names = read_npy(path, WHAT), None
        elif name.endswith(".mat"):
            weights, names = _read_mat(path), None
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
                                f"({exc}); give an (N, N) array of weights or {FORMATS} file.") from None
    return checked(weights, names, f"the {type(matrix).__name__} given")


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
        raise BrainPainterError(
            f"connectome matrix {source!r} {what}; a connectivity matrix is square (N x N, one row and one "
            "column per node). Give the whole N x N matrix (names, if any, in the first row and column).")
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
    """Weights and names of a text matrix; names from a header row and/or a first column."""
    from brainpainter.io.readers import parse_bytes

    raw = read_input(path, WHAT, max_bytes(), hint=f"give {FORMATS}", env=ENV)
    if not raw.strip():
        raise BrainPainterError(f"connectome matrix {str(path)!r} is empty; give an N x N matrix of weights "
                                "(names, if any, in the first row and column).")
    table = parse_bytes(raw, str(path), path.suffix.lower())
    grid: list[list[Any]] = [list(table.header), *table.rows]
    if _numbered_index(grid):  # pandas' to_csv of an unnamed matrix: a header and a column of 0..N-1
        grid = [r[1:] for r in grid[1:]]
    named_columns = any(is_text(c) for c in grid[0][1:]) or (len(grid[0]) == 1 and is_text(grid[0][0]))
    data = grid[1:] if named_columns else grid
    named_rows = bool(data) and all(is_text(r[0]) for r in data)
    column_names = None
    if named_columns:
        head = [str(c).strip() for c in grid[0]]
        column_names = head[1:] if named_rows or len(head) == len(data) + 1 else head
    row_names = [str(r[0]).strip() for r in data] if named_rows else None
    cells = [r[1:] for r in data] if named_rows else data
    weights = _numbers(cells, table.decimal_comma, str(path), 1 + named_columns, 1 + named_rows)
    if row_names is not None and column_names is not None and row_names != column_names:
        k = next(i for i, (a, b) in enumerate(zip(row_names, column_names, strict=False)) if a != b) \
            if len(row_names) == len(column_names) else min(len(row_names), len(column_names))
        raise BrainPainterError(
            f"connectome matrix {str(path)!r}: its row names and column names differ (row {k + 1} is "
            f"{_at(row_names, k)!r}, column {k + 1} is {_at(column_names, k)!r}); rows and columns must be "
            "the same nodes in the same order.")
    names = row_names if row_names is not None else column_names
    return weights, None if names is None else tuple(names)


def _numbered_index(grid: list[list[Any]]) -> bool:
    """Whether the first row and column are an empty corner and the counts 0..N-1 (or 1..N)."""
    if str(grid[0][0]).strip() or len(grid) != len(grid[0]):
        return False
    head, first = [to_number(c) for c in grid[0][1:]], [to_number(r[0]) for r in grid[1:]]
    n = len(head)
    return head == first and head in ([float(i) for i in range(n)], [float(i + 1) for i in range(n)])


def _at(names: list[str], k: int) -> str:
    return names[k] if k < len(names) else "(none)"


def _numbers(cells: list[list[Any]], decimal_comma: bool, source: str, line0: int,
             col0: int) -> NDArray[np.float64]:
    """The cells as floats (empty cells NaN); the first cell that is no number is an error."""
    try:
        return np.array(cells, dtype=np.float64)  # the common case: every cell a plain number
    except ValueError:
        pass
    out = np.full((len(cells), len(cells[0]) if cells else 0), np.nan)
    for i, row in enumerate(cells):
        for j, cell in enumerate(row):
            value = to_number(cell, decimal_comma)
            if value is None:
                raise BrainPainterError(
                    f"connectome matrix {source!r}: row {i + line0}, column {j + col0} is "
                    f"{str(cell)[:40]!r}, not a number; a matrix holds numbers (empty or NaN for no edge), "
                    "with names only in its first row and column.")
            out[i, j] = value
    return out


# -- binary ------------------------------------------------------------------------------------
def _limit_error(path: Path, shape: tuple[int, ...], limit: int, what: str = WHAT) -> BrainPainterError:
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
    limit = max_bytes()
    size = check_input(path, what, limit, hint=f"give a .npy file of {ndim} dimension(s)").stat().st_size
    fmt: Any = np.lib.format  # numpy's header readers are untyped
    try:
        with path.open("rb") as fh:
            version = fmt.read_magic(fh)
            reader = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
            shape, _, dtype = reader(fh)
            offset = fh.tell()
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"{what} {str(path)!r} is not a readable .npy file ({exc}); save "
                                "the matrix with numpy.save.") from None
    if dtype.hasobject or dtype.kind not in "biuf":
        raise BrainPainterError(f"{what} {str(path)!r} holds {dtype} values; a matrix holds numbers "
                                "(save a float array with numpy.save).")
    if math.prod(shape) * 8 > limit:
        raise _limit_error(path, tuple(shape), limit, what)
    if len(shape) != ndim:
        raise BrainPainterError(f"{what} {str(path)!r} holds a {len(shape)}-D array of shape "
                                f"{tuple(shape)}; it must have {ndim} dimension(s). Save the right array "
                                "with numpy.save.")
    if math.prod(shape) * dtype.itemsize > size - offset:
        raise BrainPainterError(
            f"{what} {str(path)!r} declares a {' x '.join(map(str, shape))} {dtype} array but holds "
            f"only {size - offset} bytes of data; the file is cut short or broken. Save it again with "
            "numpy.save.")
    try:
        array = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"{what} {str(path)!r} could not be read ({exc}); save it again "
                                "with numpy.save.") from None
    return np.asarray(array, dtype=np.float64)


_MAT_NUMERIC = ("double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                "logical")


def _read_mat(path: Path) -> NDArray[np.float64]:
    """The one 2-D numeric variable of a MATLAB file (or its one square one), its size checked first."""
    import scipy.io

    limit = max_bytes()
    check_input(path, WHAT, limit, hint=f"give {FORMATS}")
    try:
        variables = scipy.io.whosmat(str(path))
    except NotImplementedError:  # scipy: "Please use HDF reader for matlab v7.3 files"
        raise BrainPainterError(
            f"connectome matrix {str(path)!r} is a MATLAB v7.3 (HDF5) file, which is not read; save it with "
            "save(FILE, 'W', '-v7'), or as CSV.") from None
    except Exception as exc:  # scipy raises many types for a broken file
        raise BrainPainterError(f"connectome matrix {str(path)!r} is not a readable MATLAB .mat file "
                                f"({type(exc).__name__}: {exc}); save it again with MATLAB's save.") from None
    # MATLAB keeps every number 2-D: a scalar is 1 x 1, a vector 1 x n
    matrices = [(n, tuple(s)) for n, s, cls in variables
                if len(s) == 2 and min(s) > 1 and cls in _MAT_NUMERIC]
    square = [(n, s) for n, s in matrices if s[0] == s[1]]
    pick = matrices if len(matrices) == 1 else square if len(square) == 1 else []
    if not pick:
        shown = ", ".join(f"{n} ({' x '.join(map(str, s))} {cls})" for n, s, cls in variables) or "nothing"
        raise BrainPainterError(
            f"connectome matrix {str(path)!r} holds {shown}; it needs exactly one 2-D numeric (square) "
            "variable. Save the matrix alone (save(FILE, 'W')) or as CSV.")
    name, shape = pick[0]
    if math.prod(shape) * 8 > limit:
        raise _limit_error(path, shape, limit)
    try:
        array = scipy.io.loadmat(str(path), variable_names=[name])[name]
    except Exception as exc:
        raise BrainPainterError(f"connectome matrix {str(path)!r}: variable {name!r} could not be read "
                                f"({type(exc).__name__}: {exc}); save it again with MATLAB's save.") from None
    return np.asarray(array, dtype=np.float64)


def _read_pconn(path: Path) -> tuple[NDArray[np.float64], tuple[str, ...]]:
    """A CIFTI-2 parcel-by-parcel matrix and its parcel names (checked to be the same on both axes)."""
    import nibabel as nib

    limit = max_bytes()
    size = check_input(path, WHAT, 1024 * 2**20, hint=f"give {FORMATS}").stat().st_size
    try:
        img: Any = nib.load(str(path))
        axes = [img.header.get_axis(i) for i in range(2)]
    except Exception as exc:  # nibabel raises many types for a broken header
        raise BrainPainterError(f"connectome matrix {str(path)!r} is not a readable CIFTI-2 file "
                                f"({type(exc).__name__}: {exc}); give a .pconn.nii (or {FORMATS}).") from None
    if not all(isinstance(a, nib.cifti2.cifti2_axes.ParcelsAxis) for a in axes):
        kinds = [type(a).__name__ for a in axes]
        raise BrainPainterError(
            f"connectome matrix {str(path)!r} is a CIFTI-2 file with axes {kinds}; a connectome is a "
            ".pconn.nii (parcels by parcels). Give a parcellated connectivity file (wb_command "
            "-cifti-parcellate).")
    shape = tuple(int(s) for s in img.shape)
    if math.prod(shape) * 8 > limit:
        raise _limit_error(path, shape, limit)
    if not str(path).lower().endswith(".gz") and math.prod(shape) * img.get_data_dtype().itemsize > size:
        raise BrainPainterError(f"connectome matrix {str(path)!r} declares {' x '.join(map(str, shape))} "
                                "values but the file is shorter; it is cut short. Save it again.")
    rows, columns = (tuple(str(n) for n in a.name) for a in axes)
    if rows != columns:
        raise BrainPainterError(f"connectome matrix {str(path)!r}: its two parcel axes name different "
                                "parcels; a connectome has the same parcels as rows and columns.")
    try:
        weights = np.asarray(img.get_fdata(dtype=np.float64))
    except Exception as exc:
        raise BrainPainterError(f"connectome matrix {str(path)!r}: the data could not be read "
                                f"({type(exc).__name__}: {exc}); save it again.") from None
    return weights, rows


