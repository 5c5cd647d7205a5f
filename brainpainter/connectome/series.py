"""A series of connectivity matrices (time points, stages, conditions): one image each, read one at a time.

A series is given (as ``--connectome``) as

* several files: ``a.csv,b.csv`` (in that order), a folder (its matrix files) or a glob
  ``"fc/*.csv"`` (both sorted by name, numbers by value: ``t2`` before ``t10``); each image is named
  after its file (``a``, ``b``); every file is read as one matrix (:func:`~.matrix.read_matrix`);
* a 3-D ``.npy`` of T x N x N, read through a memory map one matrix at a time (so a 1,000-frame
  series of 400 x 400 float64, 1.3 GB, never is in memory at once);
* a ``.mat`` whose one 3-D numeric variable is N x N x T (MATLAB's order: time last), read whole
  (within the input limit);
* in Python: a 3-D array (T, N, N), or a list of files or of 2-D arrays.

The images of an array are named ``stage-1`` ... ``stage-T``.

What is drawn (:func:`series_connectome`): every matrix is read once and its edges chosen as a
single matrix's are (``--edge-threshold``, ``--top-edges`` and ``--edges-of`` apply to each matrix
in turn). The edges drawn in every image are the union of the matrices' chosen edges, so that an
edge is seen to strengthen, fade or change sign from image to image: each is coloured by its weight
in that image's matrix (0, the middle of the diverging scale, where that matrix has no such edge).
The edges' colour scale spans the chosen weights of every matrix, so colours compare across images;
an edge's width (one geometry for the series) is its largest ``|weight|`` over the series. A movie
interpolates the weights between consecutive matrices (:meth:`EdgeSeries.at`).
"""

from __future__ import annotations

import glob
import os
import re
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.matrix import SQUARE, WHAT, Matrix, checked, limit_error, read_mat, read_matrix
from brainpainter.errors import BrainPainterError

if TYPE_CHECKING:
    from collections.abc import Callable

    from brainpainter.connectome.model import Connectome

#: Files a folder of matrices holds (other files in it are passed over).
MATRIX_SUFFIXES = (".csv", ".tsv", ".txt", ".edge", ".npy", ".mat", ".pconn.nii")
#: Weights sampled from each matrix's chosen edges to choose the edges' colour scale (its quantiles: all of
#: them up to this many), so that the sample of a long series stays small.
SCALE_SAMPLES = 1000


@dataclass(frozen=True, eq=False)
class MatrixSeries:
    """Matrices read one at a time.

    Attributes
    ----------
    source : str
        What was given, for messages.
    names : tuple of str, (T,)
        The image of each matrix.
    files : tuple of str, (T,)
        One file per matrix (empty for an array).
    npy : str, optional
        A T x N x N ``.npy`` file, read through a memory map.
    array : ndarray, (T, N, N), optional
        The matrices in memory.
    """

    source: str
    names: tuple[str, ...]
    files: tuple[str, ...] = ()
    npy: str | None = None
    array: NDArray[Any] | None = None

    def __len__(self) -> int:
        return len(self.names)

    def label(self, t: int) -> str:
        """Matrix `t` as messages name it: its file, or its place in the array."""
        return repr(self.files[t]) if self.files else f"{t + 1} of {self.source!r}"

    def matrix(self, t: int) -> Matrix:
        """Matrix `t` (0-based), read now."""
        if self.files:
            return read_matrix(self.files[t])
        if self.npy is not None:
            data: Any = np.load(self.npy, mmap_mode="r", allow_pickle=False)
            return checked(np.array(data[t], dtype=np.float64), None, f"{self.npy} [{t + 1}]")
        assert self.array is not None
        return checked(np.array(self.array[t], dtype=np.float64), None, f"{self.source} [{t + 1}]")


def matrix_series(given: Any) -> MatrixSeries | None:
    """The series `given` names (see the module docstring); None where it is one matrix.

    Raises
    ------
    BrainPainterError
        A folder or glob with no matrix file, two files of one name, 2-D arrays of different shapes,
        a 3-D ``.npy`` or ``.mat`` of matrices that are not square, or too large.
    """
    if isinstance(given, str | os.PathLike):
        return _path_series(str(given))
    if isinstance(given, list | tuple) and given and all(isinstance(g, str | os.PathLike) for g in given):
        return _file_series([str(g) for g in given], "the files given")
    if isinstance(given, list | tuple) and given and all(isinstance(g, np.ndarray) for g in given):
        first = given[0].shape
        other = next((k for k, g in enumerate(given) if g.shape != first), None)
        if other is not None:
            raise _shape_error("the arrays given", f"array {other + 1}", given[other].shape, "array 1", first)
        given = np.stack(given)
    if isinstance(given, np.ndarray) and given.ndim == 3:
        _check_stack(given.shape, "the array given")
        return MatrixSeries("the array given", _stages(len(given)), array=given)
    return None


def _path_series(text: str) -> MatrixSeries | None:
    path = Path(text)
    if path.is_dir():
        found = [str(p) for p in path.iterdir() if p.is_file() and p.name.lower().endswith(MATRIX_SUFFIXES)]
        if not found:
            raise BrainPainterError(f"connectome folder {text!r} holds no matrix file "
                                    f"({', '.join(MATRIX_SUFFIXES)}); give a folder of one matrix per image, "
                                    "or the files.")
        return _file_series(sorted(found, key=_natural), text)
    if not path.exists() and "," in text:
        return _file_series([p.strip() for p in text.split(",") if p.strip()], text)
    if not path.exists() and any(c in text for c in "*?["):
        found = [p for p in glob.glob(text) if Path(p).is_file()]
        if not found:
            raise BrainPainterError(f"connectome pattern {text!r} matches no file; check the pattern (quote "
                                    "it in the shell), or give the files separated by commas.")
        return _file_series(sorted(found, key=_natural), text)
    name = path.name.lower()
    if name.endswith(".npy") and path.is_file():
        return _npy_series(path)
    if name.endswith(".mat") and path.is_file() and _mat_dimensions(path) == [3]:
        stack = np.moveaxis(read_mat(path, ndim=3), 2, 0)  # N x N x T, as MATLAB keeps time last
        _check_stack(stack.shape, text, time_last=True)
        return MatrixSeries(text, _stages(len(stack)), array=stack)
    return None


def _npy_series(path: Path) -> MatrixSeries | None:
    """A 3-D ``.npy`` as a series, None if it is not 3-D: numpy reads its header and maps the data (never
    unpickled, nothing read), each matrix checked against the input limit."""
    from brainpainter.io.files import check_input
    from brainpainter.io.rawtable import max_bytes

    check_input(path, WHAT, sys.maxsize)  # a regular file, however large: it is read through a memory map
    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception as exc:  # a broken header, object data, or fewer bytes than the header declares
        raise BrainPainterError(f"connectome matrix {str(path)!r} is not a readable .npy file "
                                f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]}); save it with "
                                "numpy.save.") from None
    if data.ndim != 3:
        return None
    if data.dtype.kind not in "biuf":
        raise BrainPainterError(f"connectome matrix {str(path)!r} holds {data.dtype} values; a matrix holds "
                                "numbers (save a float array with numpy.save).")
    _check_stack(data.shape, str(path))
    if data.shape[1] * data.shape[2] * 8 > max_bytes():
        raise limit_error(path, data.shape[1:], max_bytes())
    return MatrixSeries(str(path), _stages(data.shape[0]), npy=str(path))


def _mat_dimensions(path: Path) -> list[int]:
    """The dimensions of each variable of MATLAB file `path` longer than 1 in each (none where scipy cannot
    list them: the file is then read, and refused, as one matrix)."""
    import scipy.io

    try:
        variables = scipy.io.whosmat(str(path))
    except Exception:  # scipy raises many types for a broken file; read_matrix says what is wrong
        return []
    return [len(shape) for _, shape, _ in variables if min(shape) > 1]


def _check_stack(shape: tuple[int, ...], source: str, time_last: bool = False) -> None:
    """Refuse a T x N x M stack that holds no square matrix (`shape` with the matrices first; `time_last`:
    a ``.mat``, whose file has them last); where the matrices are square along the other axes, say which
    axis to move."""
    if shape[0] and shape[1] == shape[2] and shape[1]:
        return
    t, n, m = shape
    if time_last and t == m and n:  # the .mat is T x N x N
        raise BrainPainterError(
            f"connectome matrix {source!r} is {n} x {t} x {m}: {n} matrices of {t} x {m} with time first, "
            f"but a .mat series is N x N x T (MATLAB keeps time last); move the first axis last (MATLAB: "
            f"permute(fc, [2 3 1]); numpy: numpy.moveaxis(fc, 0, -1)), or save it as a T x N x N .npy.")
    if not time_last and t == n and m:  # an .npy or array of N x N x T
        raise BrainPainterError(
            f"connectome matrix {source!r} is {t} x {n} x {m}: {m} matrices of {t} x {n} with time last, but "
            f"a series array or .npy is T x N x N (time first); move the last axis first "
            f"(numpy.moveaxis(fc, -1, 0)), or save it as a .mat, which keeps time last.")
    raise BrainPainterError(f"connectome matrix {source!r} holds {shape[0]} matrices of {shape[1]} x "
                            f"{shape[2]}; a series is T x N x N (a .mat: N x N x T). {SQUARE}")


def _file_series(files: list[str], source: str) -> MatrixSeries:
    names = [_stem(f) for f in files]
    seen: dict[str, str] = {}
    for f, n in zip(files, names, strict=True):
        if n.lower() in seen:
            raise BrainPainterError(f"connectome series {source!r}: {seen[n.lower()]!r} and {f!r} would both "
                                    f"be image {n!r}; give the matrices files of different names.")
        seen[n.lower()] = f
    return MatrixSeries(source, tuple(names), files=tuple(files))


def _stem(file: str) -> str:
    name = Path(file).name
    suffix = next((s for s in MATRIX_SUFFIXES if name.lower().endswith(s)), Path(name).suffix)
    return name[:len(name) - len(suffix)] or name


def _natural(text: str) -> list[Any]:
    """A sort key: numbers by value (``t2`` before ``t10``), text without case."""
    return [(0, int(p), "") if p.isdigit() else (1, 0, p.lower()) for p in re.split(r"(\d+)", text)]


def _stages(n: int) -> tuple[str, ...]:
    return tuple(f"stage-{t + 1}" for t in range(n))


def _shape_error(source: str, this: str, shape: tuple[int, ...], first: str,
                 first_shape: tuple[int, ...]) -> BrainPainterError:
    return BrainPainterError(
        f"connectome series {source!r}: matrix {this} is {' x '.join(map(str, shape))} but matrix {first} "
        f"is {' x '.join(map(str, first_shape))}; every matrix of a series has the same nodes in the same "
        "order.")


@dataclass(frozen=True, eq=False)
class EdgeSeries:
    """The edges a series draws in every image, and each image's weights of them (read when asked).

    Attributes
    ----------
    matrices : MatrixSeries
    edge_from, edge_to : ndarray, (E,) intp
        The edges drawn (:meth:`Connectome.edges` of the series' connectome).
    directed : bool
    images : tuple of dict, (T,)
        Per image: ``image`` (its name), ``n_edges`` (the edges its matrix's own choice keeps) and
        ``weight_range`` (theirs).
    sample : ndarray, (S,) float64
        Weights of every matrix's chosen edges (up to :data:`SCALE_SAMPLES` quantiles each): what the
        edges' colour scale is chosen from.
    """

    matrices: MatrixSeries
    edge_from: NDArray[np.intp]
    edge_to: NDArray[np.intp]
    directed: bool
    images: tuple[dict[str, Any], ...]
    sample: NDArray[np.float64]
    _recent: dict[int, NDArray[np.float64]] = field(default_factory=dict, init=False, repr=False)

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_recent": {}}  # what was read stays in this process

    def __len__(self) -> int:
        return len(self.matrices)

    @property
    def names(self) -> tuple[str, ...]:
        """The image of each matrix, (T,)."""
        return self.matrices.names

    @property
    def given(self) -> str:
        """What the series was given as, for messages."""
        return self.matrices.source

    def weights(self, t: int) -> NDArray[np.float64]:
        """The weight of each edge drawn in matrix `t`, shape (E,): 0 where it has none (the last two read
        are kept: a movie's frames between two matrices read both)."""
        t = int(t)
        if t not in self._recent:
            if len(self._recent) >= 2:
                del self._recent[next(iter(self._recent))]
            self._recent[t] = self._read(t)
        return self._recent[t]

    def _read(self, t: int) -> NDArray[np.float64]:
        m = self.matrices.matrix(t).weights
        w = m[self.edge_from, self.edge_to]
        if not self.directed:  # an edge given in the lower triangle only
            w = np.where(np.isfinite(w) & (w != 0), w, m[self.edge_to, self.edge_from])
        out: NDArray[np.float64] = np.nan_to_num(w, nan=0.0)
        return out

    def at(self, image: float | tuple[int, int, float]) -> NDArray[np.float64]:
        """The edges' weights of image `image`, shape (E,); of ``(a, b, w)``: ``(1 - w) * a + w * b``
        (a movie's frame between images a and b)."""
        if not isinstance(image, tuple):
            return self.weights(round(image))
        a, b, w = image
        if a == b or not w:
            return self.weights(a)
        blended: NDArray[np.float64] = (1.0 - float(w)) * self.weights(a) + float(w) * self.weights(b)
        return blended

    def summary(self) -> dict[str, Any]:
        """The manifest's ``series``: the matrices' source, their count and each image's edges."""
        return {"source": self.matrices.source, "n_matrices": len(self), "images": list(self.images)}


def series_connectome(series: MatrixSeries, read: Callable[[Matrix], Connectome],
                      choose: Callable[[Connectome], Connectome]) -> Connectome:
    """The connectome a series draws: the nodes of its first matrix, the union of the matrices' chosen edges
    (each at its largest ``|weight|``), and the :class:`EdgeSeries` that colours them per image.

    Parameters
    ----------
    series : MatrixSeries
    read : callable
        ``read(matrix)``: the connectome of one matrix (its nodes placed, node values read).
    choose : callable
        ``choose(connectome)``: the connectome with only the edges drawn (threshold, top, edges of).

    Raises
    ------
    BrainPainterError
        A matrix of another shape, or other node names, than the first (naming both).
    """
    from brainpainter.connectome.read import edge_weights

    first = series.matrix(0)
    conn = read(first)
    n = conn.n_nodes
    keep = np.zeros((n, n), dtype=bool)
    peak = np.zeros((n, n))
    images: list[dict[str, Any]] = []
    samples: list[NDArray[np.float64]] = []
    for t in range(len(series)):
        m = first if t == 0 else series.matrix(t)
        if m.weights.shape != first.weights.shape:
            raise _shape_error(series.source, series.label(t), m.weights.shape, series.label(0),
                               first.weights.shape)
        if first.names is not None and m.names is not None and m.names != first.names:
            k = next(i for i, (a, b) in enumerate(zip(m.names, first.names, strict=True)) if a != b)
            raise BrainPainterError(
                f"connectome series {series.source!r}: matrix {series.label(t)} names node {k + 1} "
                f"{m.names[k]!r} but matrix {series.label(0)} names it {first.names[k]!r}; every matrix of a "
                "series has the same nodes in the same order.")
        chosen = choose(replace(conn, weights=edge_weights(m.weights, conn.directed, m.source)))
        source, target, weight = chosen.edges()
        keep[source, target] = True
        stronger = np.abs(weight) > np.abs(peak[source, target])
        peak[source[stronger], target[stronger]] = weight[stronger]
        images.append({"image": series.names[t], "n_edges": len(weight),
                       "weight_range": [float(weight.min()), float(weight.max())] if len(weight) else None})
        samples.append(_quantiles(weight))
    weights = np.where(keep, peak, np.nan)
    if not conn.directed:
        weights = np.where(np.isfinite(weights), weights, weights.T)
    drawn = replace(conn, weights=weights)
    source, target, _ = drawn.edges()
    return replace(drawn, series=EdgeSeries(series, source, target, conn.directed, tuple(images),
                                            np.concatenate(samples)))


def _quantiles(weight: NDArray[np.float64]) -> NDArray[np.float64]:
    """`weight`, or :data:`SCALE_SAMPLES` of its quantiles (its lowest and highest among them)."""
    if len(weight) <= SCALE_SAMPLES:
        return weight
    where = np.linspace(0, len(weight) - 1, SCALE_SAMPLES).round().astype(int)
    picked: NDArray[np.float64] = np.sort(weight)[where]
    return picked


def image_connectome(connectome: Connectome, image: int) -> Connectome:
    """`connectome` with the weights of `image` of its series at the edges it draws (0 where that matrix
    has none: still drawn), e.g. for an export's tooltips; `connectome` itself where it has no series."""
    series = connectome.series
    if series is None:
        return connectome
    source, target, _ = connectome.edges()
    weights = np.full_like(connectome.weights, np.nan)
    weights[source, target] = series.at(image)
    if not connectome.directed:
        weights[target, source] = weights[source, target]
    return replace(connectome, weights=weights)


def check_images(connectome: Connectome | None, n_images: int, what: str) -> None:
    """Refuse a series whose matrices are not one per image of the table (or maps) drawn with it; `what`:
    ``"table 'x.csv' has"``, ``"the maps have"``.

    Raises
    ------
    BrainPainterError
        `n_images` differs from the number of matrices.
    """
    series = None if connectome is None else connectome.series
    if series is not None and len(series) != n_images:
        raise BrainPainterError(
            f"connectome series {series.given!r} has {len(series)} matrices but {what} {n_images} "
            f"image(s); give one matrix per image (row i is drawn with matrix i), or draw the "
            "series alone.")
