"""One hemisphere's map file (or array) to its values: :func:`read_hemi`, the readers of every map format.

FreeSurfer morphometry ("curv" format), ``.mgh``/``.mgz``, GIfTI (also gzipped;
through :func:`brainpainter.io.gifti.read_gifti`, which follows no reference out of
the file's folder), NIfTI holding one value per vertex, ``.npy``, plain text, and
the label maps ``.annot``, ``.label.gii`` and ``.label``. A file whose first bytes
are another format than its name says is one line naming what was found.
:mod:`brainpainter.maps.inputs` pairs the hemispheres into maps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.files import MAX_DATA_FILE, inflated, read_input
from brainpainter.io.gifti import External, read_gifti
from brainpainter.io.sniff import CURV, GZIP, HEAD, MGH, NIFTI1, NIFTI2, NPY, described, what_is
from brainpainter.maps.fslr import named_space
from brainpainter.maps.resolution import FAMILY, FSLR, N_FSAVERAGE, native

#: File endings read as text, as arrays, as surface images, as label maps.
TEXT = (".txt", ".csv", ".tsv", ".1d")
SUFFIXES = (".mgh", ".mgz", ".gii", ".gii.gz", ".nii", ".nii.gz", ".npy", ".annot", ".label", *TEXT,
            "(none: FreeSurfer curv format, e.g. lh.thickness)")
#: GIfTI endings, compound ones first (gzipped GIfTI is read too).
GIFTI_ENDINGS = (".func.gii.gz", ".shape.gii.gz", ".label.gii.gz", ".gii.gz", ".func.gii", ".shape.gii",
                 ".label.gii", ".gii")


@dataclass(frozen=True)
class Hemi:
    """One hemisphere's map as read: values on fsaverage and, for label maps, the category names."""

    values: NDArray[Any]  # float32, shape (k, n), n a count of the fsaverage family or fsLR; NaN = no value
    categories: tuple[str, ...] | None = None
    colors: NDArray[Any] | None = None  # float, shape (n_categories, 3), sRGB 0-1
    space: str | None = None  # the mesh family the file's metadata names ("fsLR", "fsaverage")


def read_hemi(value: Any, hemi: str, *, external: External = "folder", n: int | None = None) -> Hemi:
    """One hemisphere's file or array (see the module docstring); `n`: its own surface's vertex count."""
    if isinstance(value, str | Path):
        return read_file(Path(value), hemi, external=external, n=n)
    arr = np.asarray(value, dtype=np.float64) if not isinstance(value, np.ndarray) else value
    return Hemi(native(_as_rows(arr, f"the {hemi} array", n), what=f"the {hemi} array", n=n))


def _as_rows(arr: NDArray[Any], what: str, n: int | None = None) -> NDArray[Any]:
    """An array as (k images, n vertices): 1-D, (k, n) or (n, k) with n a known count (or `n`)."""
    a = np.asarray(arr)
    known = {*FAMILY, *FSLR} if n is None else {n}
    if a.ndim == 2 and a.shape[0] in known and a.shape[1] not in known:
        a = a.T
    if a.ndim == 2 and 1 in a.shape:  # one image (a column of a text file), whatever its count
        a = a.reshape(1, -1)
    if a.ndim not in (1, 2) or a.size == 0:
        raise BrainPainterError(f"{what} has shape {a.shape}; a map has one value per vertex, shape (n,) "
                                "or (images, n).")
    if not np.issubdtype(a.dtype, np.number):
        raise BrainPainterError(f"{what} holds {a.dtype} values; a map holds numbers.")
    return a.astype(np.float32)


def read_file(path: Path, hemi: str, *, external: External = "folder", n: int | None = None) -> Hemi:
    """Read one hemisphere's map file (any format of :data:`SUFFIXES`); `n`: its own surface's count.

    A file whose first bytes say another format than its name (gzip data named
    ``lh.thickness``) is an error naming what was found; `external` is where a
    GIfTI may keep its data (:func:`brainpainter.io.gifti.read_gifti`).
    """
    import nibabel as nib
    from nibabel.freesurfer import read_annot, read_label, read_morph_data  # type: ignore[attr-defined]

    name = path.name.lower()
    if not path.is_file():
        raise BrainPainterError(f"map file {str(path)!r} ({hemi}) does not exist; give an existing file.")
    what = f"map file {path.name!r}"
    try:
        if not name.endswith((".gii", ".gii.gz", ".mgh", ".mgz", ".nii", ".nii.gz")):  # these: once read
            with path.open("rb") as f:
                _is_format(f.read(HEAD), name, what)
        if name.endswith(".annot"):
            labels, ctab, names = read_annot(str(path))  # type: ignore[no-untyped-call]
            return _labels(labels, [s.decode() if isinstance(s, bytes) else str(s) for s in names],
                           ctab[:, :3] / 255.0, what, n)
        if name.endswith(".label"):
            idx = read_label(str(path))  # type: ignore[no-untyped-call]
            size = n if n is not None and n > int(idx.max(initial=-1)) else next(
                (c for c in sorted(FAMILY) if c > int(idx.max(initial=-1))), N_FSAVERAGE)
            v = np.full(size, np.nan, np.float32)
            v[idx] = 1.0
            return Hemi(native(v, what=what, n=n))
        if name.endswith((".gii", ".gii.gz")):
            img = read_gifti(path, external=external, what="map file")
            return replace(_gifti(img, what, n), space=_gifti_space(img))
        if name.endswith((".mgh", ".mgz", ".nii", ".nii.gz")):
            # read whole (no file left open by a lazy proxy), inflated if gzip, bounded
            raw = inflated(read_input(path, "map file", MAX_DATA_FILE), what,
                           used=mgh_bytes if name.endswith((".mgh", ".mgz")) else None)
            found = _is_format(raw[:HEAD], name, what)
            klass: Any = {MGH: nib.MGHImage, NIFTI2: nib.Nifti2Image}.get(found or "", nib.Nifti1Image)
            frames = _surface_frames(np.asarray(klass.from_bytes(raw).dataobj), what, n)
            return Hemi(native(_as_rows(frames, what, n), what=what, n=n))
        if name.endswith(".npy"):
            return Hemi(native(_as_rows(np.load(path, allow_pickle=False), what, n), what=what, n=n))
        if name.endswith(TEXT):
            delim = "," if name.endswith(".csv") else ("\t" if name.endswith(".tsv") else None)
            return Hemi(native(_as_rows(np.loadtxt(path, delimiter=delim, ndmin=2), what, n), what=what, n=n))
        _check_old_curv(path, what)
        return Hemi(native(read_morph_data(str(path)), what=what, n=n))  # type: ignore[no-untyped-call]
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel's many errors for a file that is not what its name says
        text = " ".join(str(exc).split())[:160]
        raise BrainPainterError(
            f"cannot read {what} ({hemi}): {text}. Maps are {', '.join(SUFFIXES)}.") from None


#: Bytes of an MGH header, and its element sizes by type code (FreeSurfer's ``mghformat``).
_MGH_HEADER = 284
_MGH_ITEM = {0: 1, 1: 4, 3: 4, 4: 2}
#: Bytes read after an MGH file's data: its footer (TR, flip angle, TE, TI, FoV) and tags.
_MGH_FOOTER = 64 * 1024


def mgh_bytes(head: bytes) -> int | None:
    """Bytes an MGH file uses by its header (`head`: its first bytes, at least 284): header, data and up
    to 64 KiB of footer; None where `head` is no MGH header."""
    if len(head) < _MGH_HEADER or int.from_bytes(head[:4], "big") != 1:
        return None
    dims = [int.from_bytes(head[4 + 4 * k:8 + 4 * k], "big", signed=True) for k in range(4)]
    item = _MGH_ITEM.get(int.from_bytes(head[20:24], "big"))
    if item is None or min(dims) < 1:
        return None
    return _MGH_HEADER + math.prod(dims) * item + _MGH_FOOTER


def _check_old_curv(path: Path, what: str) -> None:
    """Refuse a file read as a curv file that is neither the new format (its magic number) nor the old one
    (3-byte vertex and face counts, then 2 bytes per vertex: the size says it): random bytes named
    ``lh.thickness`` were read as thousands of made-up values."""
    with path.open("rb") as f:
        head = f.read(6)
    if what_is(head) == CURV:
        return
    size = path.stat().st_size
    if len(head) == 6 and size == 6 + 2 * int.from_bytes(head[:3], "big"):
        return
    raise BrainPainterError(
        f"cannot read {what}: it is not a FreeSurfer curv file ({size:,} bytes; its first bytes are neither "
        "a curv, MGH, GIfTI nor any other format known here); give the file FreeSurfer wrote (lh.thickness, "
        "lh.sulc), an .mgh/.mgz or a .gii, named for what it holds (docs/maps.md: the formats).")


def _is_format(head: bytes, name: str, what: str) -> str | None:
    """What a file's first bytes `head` are (:func:`brainpainter.io.sniff.what_is`), if its name allows it.

    Raises
    ------
    BrainPainterError
        The bytes are another format than the name says (``'lh.thickness' looks like gzip-compressed
        data, not a FreeSurfer curv file``).
    """
    found = what_is(head)
    expected, allowed = next((f for ends, f in _FORMATS if name.endswith(ends)), _CURV)
    if found in allowed:
        return found
    hint = ("gunzip it first (a gzipped GIfTI is read when named .gii.gz)" if found == GZIP else
            "give the file your software wrote, or name it for what it holds (docs/maps.md: the formats)")
    if found is None:
        raise BrainPainterError(f"cannot read {what}: it is not {expected} (its first bytes match no format "
                                f"known here); {hint}.")
    raise BrainPainterError(f"{what} looks like {described(head)}, not {expected}; {hint}.")


#: Per file ending: the format it names and what its first bytes may be (None: no magic number).
_CURV: tuple[str, frozenset[str | None]] = ("a FreeSurfer curv file", frozenset({CURV, None}))
_FORMATS: tuple[tuple[tuple[str, ...], tuple[str, frozenset[str | None]]], ...] = (
    ((".mgh", ".mgz"), ("an MGH image", frozenset({MGH}))),
    ((".nii", ".nii.gz"), ("a NIfTI image", frozenset({NIFTI1, NIFTI2}))),
    ((".npy",), ("a NumPy .npy file", frozenset({NPY}))),
    ((".annot",), ("a FreeSurfer .annot file", frozenset({None}))),
    ((".label", *TEXT), ("a text file", frozenset({None}))),
)


def _surface_frames(data: NDArray[Any], what: str, n: int | None = None) -> NDArray[Any]:
    """An ``.mgh``/NIfTI surface overlay as (n vertices, k frames).

    ``N x 1 x 1 [x k]``, or FreeSurfer's folded form for NIfTI, whose
    dimensions are limited to 32767 (fsaverage as ``27307 x 1 x 6``): the
    vertex index runs over the first three axes, first axis fastest.
    """
    counts = {*FAMILY, *FSLR} if n is None else {n}
    if data.ndim >= 3 and int(np.prod(data.shape[:3])) in counts and 1 in data.shape[1:3]:
        return data.reshape((-1, int(np.prod(data.shape[3:], dtype=np.int64))), order="F")
    raise BrainPainterError(f"{what} has shape {data.shape}, not one value per vertex (N x 1 x 1) of an "
                            "fsaverage surface; a volume in MNI space goes to --volume.")


def _gifti_space(img: Any) -> str | None:
    """The mesh family a GIfTI image's metadata (the file's or a data array's) names (:func:`named_space`)."""
    metas = [img.meta, *(d.meta for d in img.darrays)]
    return named_space(str(v) for m in metas if m is not None for v in m.values())


def _gifti(img: Any, what: str, n: int | None = None) -> Hemi:
    arrays = [np.asarray(d.data) for d in img.darrays]
    if not arrays:
        raise BrainPainterError(f"{what} holds no data array; give a .func.gii or .shape.gii with values.")
    table = img.labeltable.get_labels_as_dict() if img.labeltable is not None else {}
    if len(table) > 1 and arrays[0].dtype.kind in "iu":
        keys = sorted(table)
        colors = np.array([[lab.red, lab.green, lab.blue] for lab in sorted(img.labeltable.labels,
                                                                            key=lambda lab: lab.key)])
        code = np.searchsorted(keys, arrays[0])
        code[~np.isin(arrays[0], keys)] = -1
        rgb = np.nan_to_num(colors.astype(float), nan=0.5)
        return _labels(code, [str(table[k]) for k in keys], rgb, what, n)
    return Hemi(native(_as_rows(np.vstack([a.reshape(1, -1) for a in arrays]), what, n), what=what, n=n))


def _labels(labels: NDArray[Any], names: list[str], colors: NDArray[Any], what: str,
            n_vertices: int | None = None) -> Hemi:
    """A label map: indices into `names` per vertex (-1 = none); medial wall and unknown get none."""
    lab = np.asarray(labels).astype(np.int64)
    v = np.where(lab >= 0, lab, np.nan).astype(np.float32)
    for i, n in enumerate(names):
        if n.lower() in ("unknown", "medial_wall", "???", "corpuscallosum") or "medial_wall" in n.lower():
            v[lab == i] = np.nan
    return Hemi(native(v, what=what, n=n_vertices), tuple(names), np.asarray(colors, float))
