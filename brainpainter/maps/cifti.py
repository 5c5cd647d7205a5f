"""CIFTI-2 files (HCP's grayordinates) as per-hemisphere vertex arrays: :func:`read_cifti`.

Read with nibabel's ``cifti2_axes``. The rows (axis 0) are the images: the
maps of a ``dscalar`` (named by the file), the label maps of a ``dlabel``
(their label tables give the categories and colours), the frames of a
``dtseries``/``ptseries`` (``--frames 0:100:10`` picks some). The columns
(axis 1) are grayordinates: a ``BrainModelAxis`` (``d*`` files) gives the
cortex from ``CORTEX_LEFT``/``CORTEX_RIGHT`` (vertex indices into the fsLR or
fsaverage mesh; vertices absent from the file, e.g. the medial wall, have no
value) and the subcortical voxels, whose mean per structure
(``CIFTI_STRUCTURE_HIPPOCAMPUS_LEFT`` -> ``Left-Hippocampus``) colours the
matching structure, as ``--volume`` does; a ``ParcelsAxis`` (``p*`` files)
gives each parcel's value to its vertices. Connectomes (``dconn``/``pconn``)
and CIFTI-1 files are refused.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.files import check_input
from brainpainter.maps.fslr import named_space
from brainpainter.maps.options import frame_rows
from brainpainter.maps.resolution import known_count

#: File endings of CIFTI files (``.dscalar.nii`` ...).
CIFTI_SUFFIXES = (".dscalar.nii", ".dlabel.nii", ".pscalar.nii", ".dtseries.nii", ".ptseries.nii")
#: CIFTI kinds that are connectomes (two grayordinate axes).
CONNECTOMES = (".dconn.nii", ".pconn.nii", ".pdconn.nii", ".dpconn.nii", ".pconnseries.nii",
               ".pconnscalar.nii")
_CORTEX = {"CIFTI_STRUCTURE_CORTEX_LEFT": "lh", "CIFTI_STRUCTURE_CORTEX_RIGHT": "rh"}
#: CIFTI subcortical structures (without side) -> the atlases' region names (FreeSurfer's aseg).
_STRUCTURES = {"ACCUMBENS": "Accumbens-area", "AMYGDALA": "Amygdala", "CAUDATE": "Caudate",
               "CEREBELLUM": "Cerebellum-Cortex", "CEREBELLAR_WHITE_MATTER": "Cerebellum-White-Matter",
               "DIENCEPHALON_VENTRAL": "VentralDC", "HIPPOCAMPUS": "Hippocampus", "PALLIDUM": "Pallidum",
               "PUTAMEN": "Putamen", "THALAMUS": "Thalamus"}
#: Values drawn may be at most this multiple of the file's data (and at least 64 MiB): a parcel
#: file's few values spread over every vertex must not grow without bound.
GROWTH = 4
#: The largest CIFTI file read (an HCP dtseries of 1200 frames is 440 MB).
MAX_BYTES = 16 * 2**30
_FLOOR = 64 * 2**20


@dataclass(frozen=True)
class Cifti:
    """What a CIFTI file holds, as :class:`~brainpainter.maps.inputs.VertexMaps` takes it.

    Attributes
    ----------
    values : dict of str to ndarray of float32, shape (k, n)
        Per hemisphere in the file, ``n`` its mesh's vertex count (NaN where the file has no value).
    images : tuple of str
    categories : tuple of str, optional
        A dlabel's label names (``values`` index them).
    category_colors : ndarray of float, shape (n_categories, 3), optional
    source : str
    regions : dict of str to ndarray of float64, shape (k,), optional
        Mean of each subcortical structure (value maps only).
    says_fslr : bool
        Whether the file's name or metadata names fsLR.
    declared : {"fsLR", "fsaverage"}, optional
        The mesh family the file's metadata names (:func:`brainpainter.maps.fslr.named_space`).
    """

    values: dict[str, NDArray[Any]]
    images: tuple[str, ...]
    categories: tuple[str, ...] | None
    category_colors: NDArray[Any] | None
    source: str
    regions: dict[str, NDArray[Any]] | None
    says_fslr: bool
    declared: str | None = None


def is_cifti(data: Any) -> bool:
    """Whether `data` is a path named as a CIFTI file (``.dscalar.nii``, ``.dconn.nii``, ...)."""
    return isinstance(data, str | Path) and Path(data).name.lower().endswith((*CIFTI_SUFFIXES, *CONNECTOMES))


def region_key(structure: str) -> str | None:
    """The atlases' region of a CIFTI structure (``CIFTI_STRUCTURE_THALAMUS_LEFT`` -> ``Left-Thalamus``)."""
    name = structure.removeprefix("CIFTI_STRUCTURE_")
    if name == "BRAIN_STEM":
        return "Brain-Stem"
    match = re.fullmatch(r"(.+)_(LEFT|RIGHT)", name)
    if match is None or match.group(1) not in _STRUCTURES:
        return None
    return f"{match.group(2).title()}-{_STRUCTURES[match.group(1)]}"


def read_cifti(path: str | Path, frames: Any = None, *, own_mesh: bool = False) -> Cifti:
    """A CIFTI-2 file's maps, cortex per hemisphere and subcortical means per structure.

    Parameters
    ----------
    path : path
        A ``.dscalar.nii``, ``.dlabel.nii``, ``.pscalar.nii``, ``.dtseries.nii`` or ``.ptseries.nii``.
    frames : str or sequence of int, optional
        The rows to read (``"0:100:10"``, ``"3"``, ``[0, 5]``); all when None.
    own_mesh : bool
        Drawn on the user's own surfaces (``--lh-surface``): any vertex count (their own) is taken.

    Returns
    -------
    Cifti
    """
    import nibabel as nib

    p = Path(path)
    name = p.name.lower()
    if name.endswith(CONNECTOMES):
        raise BrainPainterError(
            f"{p.name!r} is a CIFTI connectome (dconn/pconn), not a map: draw a pconn with --connectome "
            f"{p.name} (its parcels as nodes; docs/connectomes.md), or give one row of it as a dscalar "
            "(wb_command -cifti-merge ... or -cifti-reduce).")
    check_input(p, "CIFTI file", limit=MAX_BYTES, hint="give a CIFTI-2 file")  # a regular file, not a FIFO
    what = f"CIFTI file {p.name!r}"
    _refuse_cifti1(p, what)
    img: Any
    rows_axis: Any
    cols_axis: Any
    try:
        img = nib.load(str(p), mmap=False)
        rows_axis, cols_axis = img.header.get_axis(0), img.header.get_axis(1)
    except Exception as exc:  # nibabel's many errors for a file that is not CIFTI-2
        text = " ".join(str(exc).split())[:160]
        raise BrainPainterError(
            f"cannot read {what}: {text}. Give a CIFTI-2 {'/'.join(CIFTI_SUFFIXES)} file.") from None
    axes = nib.cifti2.cifti2_axes
    if isinstance(rows_axis, axes.BrainModelAxis | axes.ParcelsAxis):
        raise BrainPainterError(f"{what} has grayordinates on both axes (a connectome): brainpainter draws "
                                "maps, not connectomes yet; give a dscalar, dlabel, pscalar, dtseries or "
                                "ptseries.")
    if not isinstance(cols_axis, axes.BrainModelAxis | axes.ParcelsAxis):
        raise BrainPainterError(f"{what} has no grayordinates on its second axis; give a dscalar, dlabel, "
                                "pscalar, dtseries or ptseries.")
    rows = frame_rows(frames, len(rows_axis), what)
    nvertices = {_CORTEX[s]: int(n) for s, n in cols_axis.nvertices.items() if s in _CORTEX}
    for hemi, n in nvertices.items():
        if not own_mesh:
            known_count(n, f"{what} ({hemi})")
    need = 4 * len(rows) * sum(nvertices.values())
    have = _check_size(img, (len(rows_axis), len(cols_axis)), p.stat().st_size, what)
    if need > max(GROWTH * have, _FLOOR):
        raise BrainPainterError(
            f"{what}: {len(rows)} rows over {sum(nvertices.values())} vertices take {need // 2**20} MiB, "
            f"more than {GROWTH} times the file's data; pick fewer rows with --frames (e.g. --frames 0:10).")
    dtype = np.float64 if isinstance(rows_axis, axes.LabelAxis) else np.float32
    try:
        if rows == list(range(len(rows_axis))):
            data = np.asarray(img.dataobj, dtype=dtype).reshape(len(rows), -1)
        else:  # row by row: nibabel's proxy takes no list of rows
            data = np.stack([np.asarray(img.dataobj[r], dtype=dtype).reshape(-1) for r in rows])
    except Exception as exc:  # a file shorter than its header says, or data nibabel cannot convert
        text = " ".join(str(exc).split())[:160]
        raise BrainPainterError(f"cannot read the data of {what}: {text}. The file is damaged or "
                                "truncated; write it again.") from None
    labels = _label_table(rows_axis, rows) if isinstance(rows_axis, axes.LabelAxis) else None
    if labels is not None:
        data = labels[1](data)
    values, regions = _grayordinates(cols_axis, data, nvertices, labels is None, what)
    if not values and not regions:
        raise BrainPainterError(f"{what} holds no cortex (CORTEX_LEFT/CORTEX_RIGHT) and no subcortical "
                                "structure brainpainter draws.")
    return Cifti(values, _image_names(rows_axis, rows, p), labels[0] if labels else None,
                 labels[2] if labels else None, f"cifti={p.name}", regions or None, _says_fslr(p.name, img),
                 named_space(_metadata(img)))


def _grayordinates(cols_axis: Any, data: NDArray[Any], nvertices: dict[str, int], means: bool,
                   what: str) -> tuple[dict[str, NDArray[Any]], dict[str, NDArray[Any]]]:
    """The rows `data` (k, columns) spread over the cortex vertices (k, n) per hemisphere, and
    (with `means`) the mean of each subcortical structure (k,)."""
    from nibabel.cifti2 import cifti2_axes as axes

    values = {hemi: np.full((len(data), n), np.nan, np.float32) for hemi, n in nvertices.items()}
    regions: dict[str, NDArray[Any]] = {}
    if isinstance(cols_axis, axes.BrainModelAxis):
        for structure, cols in _structures(cols_axis):
            if structure in _CORTEX:
                hemi = _CORTEX[structure]
                vertex = np.asarray(cols_axis.vertex[cols], np.int64)
                if len(vertex) and (vertex.min() < 0 or vertex.max() >= nvertices[hemi]):
                    raise BrainPainterError(f"{what}: a {hemi} vertex index is outside its mesh of "
                                            f"{nvertices[hemi]} vertices; the file is damaged.")
                values[hemi][:, vertex] = data[:, cols]
            elif means and (key := region_key(structure)) is not None:
                with warnings.catch_warnings():  # a structure of NaNs: NaN, no "mean of empty slice"
                    warnings.simplefilter("ignore", RuntimeWarning)
                    regions[key] = np.nanmean(data[:, cols].astype(np.float64), axis=1)
    else:
        for j, parcel in enumerate(cols_axis.vertices):
            for structure, vertex in parcel.items():
                if structure in _CORTEX:
                    hemi = _CORTEX[structure]
                    vertex = np.asarray(vertex, np.int64)
                    if len(vertex) and (vertex.min() < 0 or vertex.max() >= nvertices[hemi]):
                        raise BrainPainterError(f"{what}: a {hemi} vertex index is outside its mesh of "
                                                f"{nvertices[hemi]} vertices; the file is damaged.")
                    values[hemi][:, vertex] = data[:, j][:, None]
    return values, regions


def _structures(axis: Any) -> list[tuple[str, slice]]:
    """The brain structures of a BrainModelAxis in their order along it, with the columns of each.

    As nibabel's ``iter_structures`` without building an axis per structure (which converts every
    column's name again: a third of the time of reading a 91k file).
    """
    names = np.asarray(axis.name)
    if not len(names):
        return []
    starts = [0, *(np.flatnonzero(names[1:] != names[:-1]) + 1).tolist()]
    ends = [*starts[1:], len(names)]
    return [(str(names[a]), slice(a, b)) for a, b in zip(starts, ends, strict=True)]


def _check_size(img: Any, axes_shape: tuple[int, int], file_size: int, what: str) -> int:
    """The bytes of the file's data, checked against its axes and the file's size (before reading).

    Raises
    ------
    BrainPainterError
        Data of another shape than the axes, or more data than the file holds (nothing is allocated).
    """
    shape = tuple(int(n) for n in img.shape)
    if shape != axes_shape:
        raise BrainPainterError(f"{what} holds data of shape {shape} but its axes say {axes_shape}; the file "
                                "is damaged; write it again.")
    size = int(np.prod(shape, dtype=np.int64)) * int(img.get_data_dtype().itemsize)
    if size > file_size:
        raise BrainPainterError(f"{what} says it holds {size} bytes of data but the file has {file_size}; it "
                                "is truncated or damaged; write it again.")
    return size


def _refuse_cifti1(path: Path, what: str) -> None:
    """A CIFTI-1 file (nibabel reads CIFTI-2 only): a one-line refusal saying how to convert it."""
    with path.open("rb") as fh:
        head = fh.read(4096)
    if b"<CIFTI" in head and re.search(rb'<CIFTI[^>]*Version\s*=\s*"1', head):
        raise BrainPainterError(
            f"{what} is CIFTI-1, which nibabel (and brainpainter) cannot read; convert it to CIFTI-2: "
            f"wb_command -file-convert -cifti-version-convert {path.name} 2 OUT{_suffix(path.name)}")


def _suffix(name: str) -> str:
    low = name.lower()
    return next((s for s in (*CIFTI_SUFFIXES, *CONNECTOMES) if low.endswith(s)), ".nii")


def _says_fslr(name: str, img: Any) -> bool:
    """Whether the file's name or metadata names fsLR (``fs_LR``, ``fsLR``)."""
    return any(re.search(r"fs_?lr", t, re.IGNORECASE) for t in [name, *_metadata(img)])


def _metadata(img: Any) -> list[str]:
    """The values of a CIFTI file's metadata (none where it has none or odd ones)."""
    try:
        return [str(v) for v in (img.header.matrix.metadata or {}).values()]
    except Exception:  # no or odd metadata
        return []


def _image_names(axis: Any, rows: list[int], path: Path) -> tuple[str, ...]:
    stem = path.name
    low = stem.lower()
    for s in (*CIFTI_SUFFIXES, *CONNECTOMES):
        if low.endswith(s):
            stem = stem[: -len(s)]
            break
    names = [str(axis.name[i]).strip() for i in rows] if hasattr(axis, "name") else []
    if names and all(names) and len(set(names)) == len(names):
        return tuple(names)
    if len(rows) == 1:
        return (stem,)
    width = len(str(max(rows)))
    return tuple(f"{stem}_{i:0{width}d}" for i in rows)


def _label_table(axis: Any, rows: list[int]) -> tuple[tuple[str, ...], Any, NDArray[Any]]:
    """(category names, keys -> category indices (NaN = none), colours (n, 3)) of a dlabel's rows."""
    index: dict[str, int] = {}  # category name -> its index (a dict: thousands of labels stay linear)
    rgb: list[tuple[float, float, float]] = []
    lookups: list[dict[int, float]] = []
    for i in rows:
        lookup: dict[int, float] = {}
        for key, (label, colour) in axis.label[i].items():
            label = str(label)
            if label in ("???", "") or label.lower() == "unknown" or "medial_wall" in label.lower():
                continue
            if label not in index:
                index[label] = len(index)
                rgb.append(_label_colour(label, colour))
            lookup[int(key)] = float(index[label])
        lookups.append(lookup)
    names = list(index)

    def code(data: NDArray[Any]) -> NDArray[Any]:
        out = np.full(data.shape, np.nan, np.float32)
        for r, lookup in enumerate(lookups):
            keys = np.rint(data[r]).astype(np.int64)
            for key, idx in lookup.items():
                out[r, keys == key] = idx
        return out

    return tuple(names), code, np.asarray(rgb, float).reshape(-1, 3)


def _label_colour(label: str, colour: Any) -> tuple[float, float, float]:
    """A label table's colour as (r, g, b) in 0..1.

    Raises
    ------
    BrainPainterError
        A component that is not a number from 0 to 1 (NaN, inf).
    """
    try:
        rgb = tuple(float(c) for c in list(colour)[:3])
    except (TypeError, ValueError):
        rgb = ()
    if len(rgb) != 3 or not all(0.0 <= c <= 1.0 for c in rgb):  # NaN fails every comparison
        shown = label if len(label) <= 40 else label[:39] + "\u2026"
        raise BrainPainterError(f"the colour of label {shown!r} in the file's label table is {list(rgb)}; "
                                "each of red, green and blue must be a number from 0 to 1. Fix the label "
                                "table (e.g. wb_command -cifti-label-import) and give the file again.")
    return rgb[0], rgb[1], rgb[2]
