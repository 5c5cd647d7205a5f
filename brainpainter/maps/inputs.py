"""Map inputs to per-hemisphere vertex arrays: :func:`read_maps`, the one entry for every kind of map.

Files (read with nibabel): FreeSurfer morphometry ("curv" format,
``lh.thickness``), ``.mgh``/``.mgz``, GIfTI ``.func.gii``/``.shape.gii`` (several
data arrays = several images; also gzipped, ``.gii.gz``), NIfTI holding one value per vertex (``N x 1 x 1``
[``x k``]), ``.npy``, plain text (one number per line; columns = images);
label maps ``.annot``, ``.label.gii`` (categories, drawn in their own colours)
and FreeSurfer ``.label`` vertex lists (a highlighted area). Arrays:
``{"lh": ndarray (n,) or (k, n), "rh": ...}`` (also ``left``/``right``, and
nilearn's ``SurfaceImage``). Every map is kept at its own resolution and
brought to fsaverage when drawn (:func:`brainpainter.maps.resolution.to_fsaverage`). A volume in MNI space is
turned into the same arrays by ``brainpainter.maps.volume`` and handed to
:func:`read_maps` as a dict.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.files import MAX_DATA_FILE, inflated, read_input
from brainpainter.io.gifti import External, read_gifti
from brainpainter.io.sniff import CURV, GZIP, HEAD, MGH, NIFTI1, NIFTI2, NPY, described, what_is
from brainpainter.maps.resolution import FAMILY, N_FSAVERAGE, native, to_fsaverage

if TYPE_CHECKING:
    from brainpainter.maps.volume import Method

HEMIS = ("lh", "rh")
#: File endings read as text, as arrays, as surface images, as label maps.
TEXT = (".txt", ".csv", ".tsv", ".1d")
SUFFIXES = (".mgh", ".mgz", ".gii", ".gii.gz", ".nii", ".nii.gz", ".npy", ".annot", ".label", *TEXT,
            "(none: FreeSurfer curv format, e.g. lh.thickness)")
#: GIfTI endings, compound ones first (gzipped GIfTI is read too).
GIFTI_ENDINGS = (".func.gii.gz", ".shape.gii.gz", ".label.gii.gz", ".gii.gz", ".func.gii", ".shape.gii",
                 ".label.gii", ".gii")
#: lh/rh spellings in file names: FreeSurfer's ``lh.``, BIDS' ``hemi-L``, and ``_lh``/``.L.``.
_PAIRS = ((r"(^|[._-])lh([._-])", r"\1rh\2"), (r"hemi-L", "hemi-R"), (r"([._-])L([._-])", r"\1R\2"),
          (r"(^|[._-])left([._-])", r"\1right\2"))


@dataclass(frozen=True)
class Hemi:
    """One hemisphere's map as read: values on fsaverage and, for label maps, the category names."""

    values: NDArray[Any]  # float32, shape (k, n), n a count of the fsaverage family; NaN = no value
    categories: tuple[str, ...] | None = None
    colors: NDArray[Any] | None = None  # float, shape (n_categories, 3), sRGB 0-1


@dataclass(frozen=True)
class VertexMaps:
    """Maps on fsaverage, ready to colour.

    Attributes
    ----------
    values : dict of str to ndarray of float32, shape (k, n)
        Per hemisphere given (``lh``/``rh``), at the map's own resolution (``n``
        a count of the fsaverage family; :meth:`on_fsaverage` brings one image
        to fsaverage); a hemisphere absent shows the underlay.
    images : tuple of str
        Name of each of the ``k`` images.
    categories : tuple of str, optional
        Label maps: ``values`` are indices into these names (NaN = unlabelled).
    category_colors : ndarray of float, shape (n_categories, 3), optional
    source : str
        What was read, for messages and the manifest.
    regions : dict of str to ndarray of float64, shape (k,), optional
        Values of whole regions beside the map, per image (a volume's mean in each
        subcortical structure, keyed as the atlases' regions: ``"Left-Hippocampus"``).
    own_mesh : bool
        The values are per vertex of the user's own surfaces (``--lh-surface``), drawn as
        they are (:meth:`on_surface`), not on fsaverage.
    """

    values: dict[str, NDArray[Any]]
    images: tuple[str, ...]
    categories: tuple[str, ...] | None = None
    category_colors: NDArray[Any] | None = None
    source: str = ""
    regions: dict[str, NDArray[Any]] | None = None
    own_mesh: bool = False

    @property
    def n_images(self) -> int:
        return len(self.images)

    def on_fsaverage(self, hemi: str, image: int) -> NDArray[Any]:
        """Image `image` of hemisphere `hemi` on fsaverage, float32 (163842,)."""
        row: NDArray[Any] = to_fsaverage(self.values[hemi][image], self.categories is not None)[0]
        return row

    def on_surface(self, hemi: str, image: int) -> NDArray[Any]:
        """Image `image` of `hemi` on the surface it is drawn on: the user's own as given, else fsaverage."""
        if self.own_mesh:
            row: NDArray[Any] = self.values[hemi][image]
            return row
        return self.on_fsaverage(hemi, image)

    def finite(self) -> NDArray[Any]:
        """Every finite value of every image and hemisphere, shape (m,) (for the colour scale)."""
        parts = [v[np.isfinite(v)] for v in self.values.values()]
        parts += [np.asarray(v, np.float32)[np.isfinite(v)] for v in (self.regions or {}).values()]
        return np.concatenate(parts) if parts else np.zeros(0, np.float32)

    def region_values(self, image: float | tuple[int, int, float]) -> dict[str, float]:
        """The region values of image `image` (a blend of two as in the map; NaN left out)."""
        out: dict[str, float] = {}
        for key, v in (self.regions or {}).items():
            if isinstance(image, tuple):
                lo, hi, t = int(image[0]), int(image[1]), float(image[2])
            else:
                lo = int(np.floor(image))
                hi, t = min(lo + 1, len(v) - 1), float(image) - lo
            x = float(v[lo]) if t == 0.0 or hi == lo else (1.0 - t) * float(v[lo]) + t * float(v[hi])
            if np.isfinite(x):
                out[key] = x
        return out

    def summary(self) -> dict[str, Any]:
        return {"kind": "vertex map", "source": self.source, "n_images": self.n_images,
                "images": list(self.images), "hemis": sorted(self.values),
                "categories": None if self.categories is None else len(self.categories),
                "regions": sorted(self.regions or {}), **({"own_mesh": True} if self.own_mesh else {})}


def pair_of(path: str | Path) -> dict[str, Path]:
    """The lh and rh files of one name (``lh.thickness`` -> ``rh.thickness`` beside it, if it exists)."""
    p = Path(path)
    for lh_pat, rh_sub in _PAIRS:
        for hemi, pat, sub in (("lh", lh_pat, rh_sub), ("rh", *_swap(lh_pat, rh_sub))):
            if re.search(pat, p.name):
                other = p.with_name(re.sub(pat, sub, p.name, count=1))
                found = {hemi: p}
                if other.is_file():
                    found["rh" if hemi == "lh" else "lh"] = other
                return found
    raise BrainPainterError(
        f"cannot tell the hemisphere of {p.name!r}: its name has no lh./rh., hemi-L/hemi-R or .L./.R.; "
        "give it with --lh FILE or --rh FILE.")


def _swap(lh_pat: str, rh_sub: str) -> tuple[str, str]:
    """The rh pattern and its lh substitution, from an lh pattern and its rh substitution."""
    table = {r"(^|[._-])lh([._-])": (r"(^|[._-])rh([._-])", r"\1lh\2"), r"hemi-L": (r"hemi-R", "hemi-L"),
             r"([._-])L([._-])": (r"([._-])R([._-])", r"\1L\2"),
             r"(^|[._-])left([._-])": (r"(^|[._-])right([._-])", r"\1left\2")}
    return table[lh_pat]


#: File endings that are maps, never tables.
MAP_ONLY_SUFFIXES = (".mgh", ".mgz", ".gii", ".gii.gz", ".nii", ".nii.gz", ".npy", ".annot", ".label")
#: FreeSurfer morphometry files ("curv" format, no ending), e.g. ``lh.thickness``, ``rh.sulc``.
_MORPH = re.compile(r"^[lr]h\.(thickness|sulc|curv|area|volume|jacobian_white|avg_curv|pial_lgi|w-g\.pct)"
                    r"(\.|$)")
_TABLE_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", ".xlsx", ".xlsm", ".xls", ".json")


def is_map_input(data: Any) -> bool:
    """Whether `data` is a map rather than a region table.

    A hemisphere dict of arrays, a surface image, or one file that is a map
    by its ending (``.mgh``, ``.gii``, ...) or a FreeSurfer morphometry name
    (``lh.thickness``, ``rh.sulc``...; not ``lh.aparc.thickness.table``, a table).
    """
    if isinstance(data, str | Path):
        name = Path(data).name.lower()
        if name.endswith(MAP_ONLY_SUFFIXES):
            return True
        return bool(_MORPH.match(name)) and not name.endswith(_TABLE_SUFFIXES)
    if isinstance(data, Mapping):
        keys = {str(k).lower() for k in data}
        return bool(keys) and keys <= {"lh", "rh", "left", "right"}
    if isinstance(data, VertexMaps):
        return True
    return hasattr(data, "data") and hasattr(data.data, "parts")  # nilearn SurfaceImage


def read_maps(data: Any = None, lh: Any = None, rh: Any = None, volume: Any = None, *,
              external: External = "folder", mesh: Mapping[str, int] | None = None) -> VertexMaps:
    """Any map input to :class:`VertexMaps` on fsaverage (the hook every command calls).

    Parameters
    ----------
    data : path, dict, nilearn SurfaceImage or VertexMaps, optional
        One file whose name says its hemisphere (its partner is found beside
        it), ``{"lh": ..., "rh": ...}`` (``left``/``right``) of arrays or paths,
        an MNI152 volume (a 3-D/4-D NIfTI file or nibabel image), or maps
        already read (returned as they are).
    lh, rh : path or ndarray, optional
        One hemisphere each (``--lh FILE --rh FILE``).
    volume : path or nibabel image, optional
        An MNI152 volume (``--volume FILE``), projected by
        :func:`read_volume`.
    external : {"folder", "refuse"}
        Where a GIfTI file may keep its data: in a file inside its own folder,
        or nowhere but in itself (the web server;
        :func:`brainpainter.io.gifti.read_gifti`).
    mesh : mapping of {"lh", "rh"} to int, optional
        The vertex counts of the user's own surfaces (``--lh-surface``/``--rh-surface``, or a
        template built from a subject): each hemisphere's map has exactly that many values and
        is drawn on that surface as it is (``own_mesh``), never on fsaverage.
    """
    from brainpainter.maps import volume as volumes

    if isinstance(data, VertexMaps) and lh is None and rh is None and volume is None:
        return data  # already read (e.g. kept by the web server)
    if volume is None and data is not None and volumes.is_volume(data):
        volume, data = data, None
    if volume is not None and mesh is not None:
        raise BrainPainterError("a volume (--volume) is projected onto fsaverage, not onto your own "
                                "surfaces (--lh-surface/--rh-surface, or a template built from a subject); "
                                "give per-vertex maps of those surfaces with --lh/--rh, or leave them out.")
    if volume is not None:
        if data is not None or lh is not None or rh is not None:
            raise BrainPainterError("give a volume (--volume) or surface maps (--lh/--rh), not both: the "
                                    "volume is projected onto both hemispheres.")
        return read_volume(volume)
    given: dict[str, Any] = {}
    if data is not None:
        if hasattr(data, "data") and hasattr(data.data, "parts"):
            data = dict(data.data.parts)
        if isinstance(data, Mapping):
            for key, value in data.items():
                hemi = {"lh": "lh", "left": "lh", "rh": "rh", "right": "rh"}.get(str(key).lower())
                if hemi is None:
                    raise BrainPainterError(f"a map dict has keys lh/rh (or left/right); {key!r} was given.")
                given[hemi] = value
        elif isinstance(data, str | Path):
            found = pair_of(data)  # a partner found beside the file is drawn only where a surface is given
            given.update({h: p for h, p in found.items() if mesh is None or h in mesh or p == Path(data)})
        else:
            raise BrainPainterError(
                f"a map is a file, or a dict {{'lh': array, 'rh': array}}; a {type(data).__name__} was "
                "given.")
    for hemi, value in (("lh", lh), ("rh", rh)):
        if value is not None:
            given[hemi] = value
    if not given:
        raise BrainPainterError("no map given: give --lh FILE and/or --rh FILE (or a dict of arrays).")
    if mesh is not None:
        missing = sorted(set(given) - set(mesh))
        if missing:
            flag = f"--{missing[0]}-surface"
            raise BrainPainterError(f"a map of {missing[0]} was given but no surface to draw it on ({flag}); "
                                    f"give {flag} FILE, or leave out the other surface to draw on fsaverage.")
    hemis = {h: read_hemi(v, h, external=external, n=None if mesh is None else mesh[h])
             for h, v in given.items()}
    maps = _combine(hemis, given)
    return maps if mesh is None else replace(maps, own_mesh=True)


def read_volume(img: Any, *, method: Method = "linear") -> VertexMaps:
    """A volume as maps on fsaverage, with its subcortical means: what ``--volume FILE`` draws.

    Parameters
    ----------
    img : path or nibabel image
        An MNI152 volume, 3-D or 4-D (one image per volume).
    method : {"linear", "nearest"}
        As in :func:`brainpainter.maps.volume.project_volume`.

    Returns
    -------
    brainpainter.maps.inputs.VertexMaps
        ``values`` of shape (n_volumes, 163842) per hemisphere, images named as in
        :func:`~brainpainter.maps.volume.volume_images`, and ``regions``: the mean inside each
        subcortical structure (:func:`~brainpainter.maps.volume.subcortical_means`), shape
        (n_volumes,) each.
    """
    from brainpainter.maps.volume import load_volume, project_volume, subcortical_means

    volume = load_volume(img)
    projected = project_volume(img, method=method)
    means = subcortical_means(img, method=method)
    k = volume.n_volumes
    if len(volume.shape) == 3:
        images: tuple[str, ...] = (volume.name,)
    else:
        width = len(str(k - 1))
        images = tuple(f"{volume.name}_{i:0{width}d}" for i in range(k))
    values = {hemi: np.asarray(v, np.float32).reshape(k, -1) for hemi, v in projected.items()}
    regions = {key: np.asarray(v, np.float64).reshape(k) for key, v in means.items()}
    return VertexMaps(values, images, source=f"volume={volume.name}", regions=regions)


def _combine(hemis: dict[str, Hemi], given: dict[str, Any]) -> VertexMaps:
    ks = {h.values.shape[0] for h in hemis.values()}
    if len(ks) > 1:
        counts = {k: h.values.shape[0] for k, h in hemis.items()}
        raise BrainPainterError(f"the hemispheres hold different numbers of images ({counts}); give the "
                                "same images for lh and rh.")
    k = ks.pop()
    labelled = [h.categories is not None for h in hemis.values()]
    categories: tuple[str, ...] | None = None
    colors: NDArray[Any] | None = None
    values = {name: h.values for name, h in hemis.items()}
    if any(labelled):
        if not all(labelled):
            raise BrainPainterError("one hemisphere is a label map and the other holds values; give two "
                                    "label maps or two value maps.")
        names: list[str] = []
        rgb: list[NDArray[Any]] = []
        for name, h in hemis.items():  # one list of names for both hemispheres
            assert h.categories is not None and h.colors is not None
            code = np.full(len(h.categories), np.nan, np.float32)
            for i, c in enumerate(h.categories):
                if c not in names:
                    names.append(c)
                    rgb.append(h.colors[i])
                code[i] = names.index(c)
            v = h.values
            ok = np.isfinite(v)
            out = np.full_like(v, np.nan)
            out[ok] = code[v[ok].astype(np.int64)]
            values[name] = out
        categories, colors = tuple(names), np.asarray(rgb, float)
    first = next(iter(given.values()))
    base = _stem(first) if isinstance(first, str | Path) else "map"
    images = (base,) if k == 1 else tuple(f"{base}-{j + 1:0{len(str(k))}d}" for j in range(k))
    source = ", ".join(f"{h}={v if isinstance(v, str | Path) else type(v).__name__}"
                       for h, v in given.items())
    return VertexMaps(values, images, categories, colors, source)


def _stem(path: str | Path) -> str:
    name = Path(path).name
    for suffix in (*GIFTI_ENDINGS, ".nii.gz", *SUFFIXES[:-1]):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    for pat in (r"(^|[._-])[lr]h([._-]|$)", r"()hemi-[LR]_?", r"(^|[._-])(?:left|right)([._-]|$)"):
        name = re.sub(pat, lambda m: m.group(1) or "", name)
    return name.strip("._-") or "map"


def read_hemi(value: Any, hemi: str, *, external: External = "folder", n: int | None = None) -> Hemi:
    """One hemisphere's file or array (see the module docstring); `n`: its own surface's vertex count."""
    if isinstance(value, str | Path):
        return read_file(Path(value), hemi, external=external, n=n)
    arr = np.asarray(value, dtype=np.float64) if not isinstance(value, np.ndarray) else value
    return Hemi(native(_as_rows(arr, f"the {hemi} array", n), what=f"the {hemi} array", n=n))


def _as_rows(arr: NDArray[Any], what: str, n: int | None = None) -> NDArray[Any]:
    """An array as (k images, n vertices): 1-D, (k, n) or (n, k) with n an fsaverage count (or `n`)."""
    a = np.asarray(arr)
    counts = FAMILY if n is None else {n}
    if a.ndim == 2 and a.shape[0] in counts and a.shape[1] not in counts:
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
            return _gifti(read_gifti(path, external=external, what="map file"), what, n)
        if name.endswith((".mgh", ".mgz", ".nii", ".nii.gz")):
            # read whole (no file left open by a lazy proxy), inflated if gzip, bounded
            raw = inflated(read_input(path, "map file", MAX_DATA_FILE), what)
            found = _is_format(raw[:HEAD], name, what)
            klass: Any = {MGH: nib.MGHImage, NIFTI2: nib.Nifti2Image}.get(found or "", nib.Nifti1Image)
            frames = _surface_frames(np.asarray(klass.from_bytes(raw).dataobj), what, n)
            return Hemi(native(_as_rows(frames, what, n), what=what, n=n))
        if name.endswith(".npy"):
            return Hemi(native(_as_rows(np.load(path, allow_pickle=False), what, n), what=what, n=n))
        if name.endswith(TEXT):
            delim = "," if name.endswith(".csv") else ("\t" if name.endswith(".tsv") else None)
            return Hemi(native(_as_rows(np.loadtxt(path, delimiter=delim, ndmin=2), what, n), what=what, n=n))
        return Hemi(native(read_morph_data(str(path)), what=what, n=n))  # type: ignore[no-untyped-call]
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel's many errors for a file that is not what its name says
        text = " ".join(str(exc).split())[:160]
        raise BrainPainterError(
            f"cannot read {what} ({hemi}): {text}. Maps are {', '.join(SUFFIXES)}.") from None


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
    counts = FAMILY if n is None else {n}
    if data.ndim >= 3 and int(np.prod(data.shape[:3])) in counts and 1 in data.shape[1:3]:
        return data.reshape((-1, int(np.prod(data.shape[3:], dtype=np.int64))), order="F")
    raise BrainPainterError(f"{what} has shape {data.shape}, not one value per vertex (N x 1 x 1) of an "
                            "fsaverage surface; a volume in MNI space goes to --volume.")


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
