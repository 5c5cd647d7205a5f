"""Map inputs to per-hemisphere vertex arrays: :func:`read_maps`, the one entry for every kind of map.

Files (read with nibabel): FreeSurfer morphometry ("curv" format,
``lh.thickness``), ``.mgh``/``.mgz``, GIfTI ``.func.gii``/``.shape.gii`` (several
data arrays = several images; also gzipped, ``.gii.gz``), NIfTI holding one value per vertex (``N x 1 x 1``
[``x k``]), ``.npy``, plain text (one number per line; columns = images);
label maps ``.annot``, ``.label.gii`` (categories, drawn in their own colours)
and FreeSurfer ``.label`` vertex lists (a highlighted area); CIFTI-2 files
(``.dscalar.nii``, ``.dlabel.nii``, ... read by :mod:`brainpainter.maps.cifti`). Arrays:
``{"lh": ndarray (n,) or (k, n), "rh": ...}`` (also ``left``/``right``, and
nilearn's ``SurfaceImage``). Every map is kept at its own resolution and
brought to fsaverage when drawn (:func:`brainpainter.maps.resolution.to_fsaverage`; fsLR maps, 32,492
vertices, or 163,842 where the file or ``space`` says fsLR, through :mod:`brainpainter.maps.fslr`).
A volume in MNI space is turned into the same arrays by ``brainpainter.maps.volume`` and handed to
:func:`read_maps` as a dict.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.io.gifti import External
from brainpainter.maps.files import GIFTI_ENDINGS, SUFFIXES, Hemi, read_hemi
from brainpainter.maps.fslr import SPACES, decide_space, named_space, names_fslr, swapped_hemispheres
from brainpainter.maps.options import frame_rows
from brainpainter.maps.resolution import native, to_fsaverage

if TYPE_CHECKING:
    from brainpainter.maps.volume import Method

HEMIS = ("lh", "rh")
#: lh/rh spellings in file names: FreeSurfer's ``lh.``, BIDS' ``hemi-L``, and ``_lh``/``.L.``.
_PAIRS = ((r"(^|[._-])lh([._-])", r"\1rh\2"), (r"hemi-L", "hemi-R"), (r"(^|[._-])L([._-])", r"\1R\2"),
          (r"(^|[._-])left([._-])", r"\1right\2"))


@dataclass(frozen=True)
class VertexMaps:
    """Maps on fsaverage, ready to colour.

    Attributes
    ----------
    values : dict of str to ndarray of float32, shape (k, n)
        Per hemisphere given (``lh``/``rh``), at the map's own resolution (``n``
        a count of the fsaverage family, or of fsLR when ``space`` is ``"fsLR"``;
        :meth:`on_fsaverage` brings one image to fsaverage); a hemisphere absent
        shows the underlay.
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
    space : {"fsaverage", "fsLR"}
        The mesh family of ``values``.
    notes : tuple of str
        What the reader decided that the user should hear (``note: ...`` on the CLI).
    own_mesh : bool
        The values are per vertex of the user's own surfaces (``--lh-surface``, or a template
        built from a subject), drawn as they are (:meth:`on_surface`), not on fsaverage.
    label : str
        What its colour bar says when no label is given; empty: its file's name (``source``).
    """

    values: dict[str, NDArray[Any]]
    images: tuple[str, ...]
    categories: tuple[str, ...] | None = None
    category_colors: NDArray[Any] | None = None
    source: str = ""
    regions: dict[str, NDArray[Any]] | None = None
    space: str = "fsaverage"
    notes: tuple[str, ...] = ()
    own_mesh: bool = False
    label: str = ""

    @property
    def n_images(self) -> int:
        return len(self.images)

    def on_fsaverage(self, hemi: str, image: int) -> NDArray[Any]:
        """Image `image` of hemisphere `hemi` on fsaverage, float32 (163842,)."""
        if self.space == "fsLR":
            from brainpainter.maps.fslr import fslr_to_fsaverage

            labels = self.categories is not None
            resampled: NDArray[Any] = fslr_to_fsaverage(self.values[hemi][image], hemi, labels)[0]
            return resampled
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
                "regions": sorted(self.regions or {}), "space": self.space, "notes": list(self.notes),
                **({"own_mesh": True} if self.own_mesh else {})}


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


def named_hemi(name: str) -> str | None:
    """The hemisphere a file name says (``rh.thickness``, ``hemi-L``, ``thick_left.gii``), or None."""
    said = {hemi for lh_pat, rh_sub in _PAIRS
            for hemi, pat in (("lh", lh_pat), ("rh", _swap(lh_pat, rh_sub)[0])) if re.search(pat, name)}
    return said.pop() if len(said) == 1 else None


def _check_side(hemi: str, value: Any) -> None:
    """Refuse a file given for `hemi` whose name says the other hemisphere (``--lh rh.thickness``: the
    right hemisphere's values were drawn on the left without a word)."""
    if not isinstance(value, str | Path):
        return
    said = named_hemi(Path(value).name)
    if said is not None and said != hemi:
        side = {"lh": "left", "rh": "right"}
        raise BrainPainterError(
            f"--{hemi} {Path(value).name!r}: its name says the {side[said]} hemisphere, but --{hemi} takes "
            f"the {side[hemi]} one's values; give it with --{said} (and the {side[hemi]} hemisphere's file "
            f"with --{hemi}), or rename it if it holds the {side[hemi]} hemisphere.")


def _swap(lh_pat: str, rh_sub: str) -> tuple[str, str]:
    """The rh pattern and its lh substitution, from an lh pattern and its rh substitution."""
    table = {r"(^|[._-])lh([._-])": (r"(^|[._-])rh([._-])", r"\1lh\2"), r"hemi-L": (r"hemi-R", "hemi-L"),
             r"(^|[._-])L([._-])": (r"(^|[._-])R([._-])", r"\1L\2"),
             r"(^|[._-])left([._-])": (r"(^|[._-])right([._-])", r"\1left\2")}
    return table[lh_pat]


#: File endings that are maps, never tables.
MAP_ONLY_SUFFIXES = (".mgh", ".mgz", ".gii", ".gii.gz", ".nii", ".nii.gz", ".npy", ".annot", ".label")
#: FreeSurfer morphometry files ("curv" format, no ending), e.g. ``lh.thickness``, ``rh.sulc``.
_MORPH = re.compile(r"^[lr]h\.(thickness|sulc|curv|area|volume|jacobian_white|avg_curv|pial_lgi|w-g\.pct)"
                    r"(\.|$)")
TABLE_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", ".xlsx", ".xlsm", ".xls", ".json")


def is_morph_name(name: str) -> bool:
    """Whether the lower-case file name `name` is a FreeSurfer morphometry file's (``lh.thickness``,
    ``rh.sulc.fwhm10``; not ``lh.aparc.thickness.table`` nor a ``.csv``: tables)."""
    return bool(_MORPH.match(name)) and not name.endswith(TABLE_SUFFIXES)


def is_map_input(data: Any) -> bool:
    """Whether `data` is a map rather than a region table.

    A hemisphere dict of arrays, a surface image, or one file that is a map
    by its ending (``.mgh``, ``.gii``, ...) or a FreeSurfer morphometry name
    (``lh.thickness``, ``rh.sulc``...; not ``lh.aparc.thickness.table``, a table).
    """
    if isinstance(data, str | Path):
        name = Path(data).name.lower()
        return name.endswith(MAP_ONLY_SUFFIXES) or is_morph_name(name)
    if isinstance(data, Mapping):
        keys = {str(k).lower() for k in data}
        return bool(keys) and keys <= {"lh", "rh", "left", "right"}
    if isinstance(data, VertexMaps):
        return True
    return hasattr(data, "data") and hasattr(data.data, "parts")  # nilearn SurfaceImage


def read_maps(data: Any = None, lh: Any = None, rh: Any = None, volume: Any = None, *,
              external: External = "folder", space: str | None = None, frames: Any = None,
              projection: str | None = None, radius: float | None = None,
              mesh: Mapping[str, int] | None = None) -> VertexMaps:
    """Any map input to :class:`VertexMaps` on fsaverage (the hook every command calls).

    Parameters
    ----------
    data : path, dict, nilearn SurfaceImage or VertexMaps, optional
        One file whose name says its hemisphere (its partner is found beside
        it), a CIFTI-2 file (``.dscalar.nii``, ``.dlabel.nii``, ...),
        ``{"lh": ..., "rh": ...}`` (``left``/``right``) of arrays or paths,
        an MNI152 volume (a 3-D/4-D NIfTI file or nibabel image), or maps
        already read (returned as they are).
    lh, rh : path or ndarray, optional
        One hemisphere each (``--lh FILE --rh FILE``); `lh` alone may be maps already read
        (VertexMaps of both hemispheres, e.g. beside a region table).
    volume : path or nibabel image, optional
        An MNI152 volume (``--volume FILE``), projected by
        :func:`read_volume`.
    external : {"folder", "refuse"}
        Where a GIfTI file may keep its data: in a file inside its own folder,
        or nowhere but in itself (the web server;
        :func:`brainpainter.io.gifti.read_gifti`).
    space : {"fsaverage", "fsLR"}, optional
        The mesh of 163,842-vertex maps when the file does not say (``--space``);
        fsaverage when neither says, with a note.
    frames : str or sequence of int, optional
        The images to keep (``--frames 0:100:10``, ``"3"``, ``[0, 4]``): frames of a series.
    projection, radius : optional
        How a volume is sampled (``--projection``, ``--projection-radius``), as in
        :func:`brainpainter.maps.volume.project_volume`.
    mesh : mapping of {"lh", "rh"} to int, optional
        The vertex counts of the user's own surfaces (``--lh-surface``/``--rh-surface``, or a
        template built from a subject): each hemisphere's map has exactly that many values and
        is drawn on that surface as it is (``own_mesh``), never resampled (nor ``space``).
    """
    from brainpainter.maps import volume as volumes
    from brainpainter.maps.cifti import is_cifti, read_cifti

    if isinstance(lh, VertexMaps) and data is None and rh is None and volume is None:
        data, lh = lh, None  # both hemispheres already read, as --lh beside a region table (the web server)
    if isinstance(data, VertexMaps) and lh is None and rh is None and volume is None:
        return pick_images(data, frames)  # already read (e.g. kept by the web server)
    if space is not None and space not in SPACES:
        raise choice_error("space", space, SPACES)
    if is_cifti(data) and lh is None and rh is None and volume is None:
        c = read_cifti(data, frames, own_mesh=mesh is not None)
        if mesh is not None:  # its cortex on the user's own (fsLR) surfaces, as it is
            return _cifti_on_mesh(c, Path(data).name, mesh)
        chosen, notes = decide_space({h: v.shape[1] for h, v in c.values.items()}, space, c.says_fslr,
                                     f"CIFTI file {Path(data).name!r}", c.declared)
        return VertexMaps(c.values, c.images, c.categories, c.category_colors, c.source, c.regions, chosen,
                          notes)
    cifti = [v for v in (data, lh, rh, volume) if is_cifti(v)]
    if cifti:
        raise BrainPainterError(f"{Path(cifti[0]).name!r} is a CIFTI file, which holds both hemispheres: "
                                "give it alone, as INPUT (brainpainter render FILE.dscalar.nii), not with "
                                "--lh/--rh.")
    if volume is None and data is not None and volumes.is_volume(data):
        volume, data = data, None
    if volume is not None and mesh is not None:
        raise BrainPainterError(VOLUME_ON_MESH)
    if volume is not None:
        if data is not None or lh is not None or rh is not None:
            raise BrainPainterError("give a volume (--volume) or surface maps (--lh/--rh), not both: the "
                                    "volume is projected onto both hemispheres.")
        return pick_images(read_volume(volume, projection=projection, radius=radius), frames)
    given = _given(data, lh, rh, mesh)
    if mesh is not None:
        return pick_images(_read_on_mesh(given, mesh, external), frames)
    hemis = {h: read_hemi(v, h, external=external) for h, v in given.items()}
    maps = _combine(hemis, given)
    says = any(names_fslr(Path(v).name) for v in given.values() if isinstance(v, str | Path))
    declared = named_space(h.space for h in hemis.values() if h.space is not None)
    chosen, notes = decide_space({h: v.shape[1] for h, v in maps.values.items()}, space, says, "the map",
                                 declared)
    if chosen == "fsLR" and maps.categories is None:
        _warn_swapped(maps, given)
    return pick_images(replace(maps, space=chosen, notes=notes), frames)


def _warn_swapped(maps: VertexMaps, given: Mapping[str, Any]) -> None:
    """Warn for an fsLR map on the other hemisphere's cortex (:func:`.fslr.swapped_hemispheres`)."""
    named = {h: f"map {Path(v).name!r}" for h, v in given.items() if isinstance(v, str | Path)}
    for line in swapped_hemispheres(maps.values, named):
        warnings.warn(line, UserWarning, stacklevel=3)


#: Why a volume is not drawn on the user's own surfaces.
VOLUME_ON_MESH = ("a volume (--volume) is projected onto fsaverage, not onto your own surfaces (--lh-surface/"
                  "--rh-surface, or a template built from a subject); give per-vertex maps of those surfaces "
                  "with --lh/--rh, or leave them out.")


def _given(data: Any, lh: Any, rh: Any, mesh: Mapping[str, int] | None) -> dict[str, Any]:
    """Hemisphere -> file or array of a surface map input (a partner file found beside one given is
    taken only where `mesh`, the user's own surfaces, has that hemisphere)."""
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
            found = pair_of(data)
            given.update({h: p for h, p in found.items() if mesh is None or h in mesh or p == Path(data)})
        else:
            raise BrainPainterError(
                f"a map is a file, or a dict {{'lh': array, 'rh': array}}; a {type(data).__name__} was "
                "given.")
    for hemi, value in (("lh", lh), ("rh", rh)):
        if value is not None:
            _check_side(hemi, value)
            given[hemi] = value
    if not given:
        raise BrainPainterError("no map given: give --lh FILE and/or --rh FILE (or a dict of arrays).")
    return given


def _read_on_mesh(given: dict[str, Any], mesh: Mapping[str, int], external: External) -> VertexMaps:
    """The maps `given`, each of its own surface's vertex count (`mesh`), to be drawn as they are."""
    missing = sorted(set(given) - set(mesh))
    if missing:
        flag = f"--{missing[0]}-surface"
        raise BrainPainterError(f"a map of {missing[0]} was given but no surface to draw it on ({flag}); "
                                f"give {flag} FILE, or leave out the other surface to draw on fsaverage.")
    hemis = {h: read_hemi(v, h, external=external, n=mesh[h]) for h, v in given.items()}
    return replace(_combine(hemis, given), own_mesh=True)


def _cifti_on_mesh(c: Any, name: str, mesh: Mapping[str, int]) -> VertexMaps:
    """A CIFTI file's cortex (:func:`~brainpainter.maps.cifti.read_cifti`) on the user's own surfaces.

    Its subcortical structures are left out, with a note: a template of your own surfaces has no
    subcortical meshes, and the template's (fsaverage's) are not in your surfaces' coordinates.
    """
    values = {h: native(v, f"CIFTI file {name!r} ({h})", n=mesh[h]) for h, v in c.values.items() if h in mesh}
    notes = () if not c.regions else (
        f"CIFTI file {name!r}: its subcortical structures ({', '.join(sorted(c.regions))}) are not drawn on "
        "your own surfaces (--lh-surface/--rh-surface), which have no subcortical meshes; render the file "
        "without them to see the structures on the template's (--views subcortical).",)
    return VertexMaps(values, c.images, c.categories, c.category_colors, c.source, None, own_mesh=True,
                      notes=notes)


def pick_images(maps: VertexMaps, frames: Any) -> VertexMaps:
    """`maps` with only the images `frames` picks (:func:`frame_rows`); all when None."""
    if frames is None:
        return maps
    rows = frame_rows(frames, maps.n_images, maps.source or "the map")
    return replace(maps, values={h: v[rows] for h, v in maps.values.items()},
                   images=tuple(maps.images[i] for i in rows),
                   regions=None if maps.regions is None else {k: v[rows] for k, v in maps.regions.items()})


def maps_to_fsaverage(data: Any, space: str | None = None) -> dict[str, NDArray[Any]]:
    """Surface maps of any mesh brainpainter knows, on fsaverage (``brainpainter.to_fsaverage``).

    Parameters
    ----------
    data : path or dict
        A CIFTI-2 file (``.dscalar.nii``, ``.dlabel.nii``, ...), one file of an lh/rh pair
        (an fsLR GIfTI such as ``L.thickness.32k_fs_LR.func.gii``), or
        ``{"lh": array or path, "rh": ...}`` on fsLR 32k/164k or the fsaverage family.
    space : {"fsaverage", "fsLR"}, optional
        The mesh of 163,842-vertex maps that do not say (default fsaverage).

    Returns
    -------
    dict of str to ndarray of float32
        ``{"lh": (163842,), "rh": (163842,)}`` for the hemispheres given, ``(k, 163842)`` for
        ``k > 1`` images; NaN outside the cortex (the medial wall) and where the map has no value.
        A label map gives indices into its categories (:func:`read_maps`'s ``categories``).
    """
    maps = read_maps(data, space=space)
    out: dict[str, NDArray[Any]] = {}
    for hemi in maps.values:
        rows = np.stack([maps.on_fsaverage(hemi, i) for i in range(maps.n_images)])
        out[hemi] = rows[0] if maps.n_images == 1 else rows
    return out


def read_volume(img: Any, *, method: Method = "linear", projection: str | None = None,
                radius: float | None = None) -> VertexMaps:
    """A volume as maps on fsaverage, with its subcortical means: what ``--volume FILE`` draws.

    Parameters
    ----------
    img : path or nibabel image
        An MNI152 volume, 3-D or 4-D (one image per volume).
    method : {"linear", "nearest"}
        As in :func:`brainpainter.maps.volume.project_volume`.
    projection : {"ribbon", "line", "point"}, optional
    radius : float, optional
        As in :func:`~brainpainter.maps.volume.project_volume` (default 3 mm).

    Returns
    -------
    brainpainter.maps.inputs.VertexMaps
        ``values`` of shape (n_volumes, 163842) per hemisphere, images named as in
        :func:`~brainpainter.maps.volume_images.volume_images`, and ``regions``: the mean inside each
        subcortical structure (:func:`~brainpainter.maps.volume.subcortical_means`), shape
        (n_volumes,) each.
    """
    from brainpainter.maps.options import RADIUS_MM, check_projection
    from brainpainter.maps.volume import load_volume, project_volume, subcortical_means

    volume = load_volume(img)
    radius = RADIUS_MM if radius is None else radius
    projected = project_volume(img, method=method, projection=check_projection(projection, method, radius),
                               radius=radius)
    means = subcortical_means(img, method=method)
    k = volume.n_volumes
    values = {hemi: np.asarray(v, np.float32).reshape(k, -1) for hemi, v in projected.items()}
    regions = {key: np.asarray(v, np.float64).reshape(k) for key, v in means.items()}
    return VertexMaps(values, volume.image_names, source=f"volume={volume.name}", regions=regions)


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
    # arrays given in memory have no name: their bar says "map", not "lh=ndarray, rh=ndarray"
    label = "" if isinstance(first, str | Path) else "map"
    return VertexMaps(values, images, categories, colors, source, label=label)


def _stem(path: str | Path) -> str:
    name = Path(path).name
    for suffix in (*GIFTI_ENDINGS, ".nii.gz", *SUFFIXES[:-1]):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    for pat in (r"(^|[._-])[lr]h([._-]|$)", r"()hemi-[LR]_?", r"(^|[._-])(?:left|right)([._-]|$)",
                r"(^|[._-])[LR]([._-]|$)"):
        name = re.sub(pat, lambda m: m.group(1) or "", name)
    return name.strip("._-") or "map"

