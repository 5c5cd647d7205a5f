"""Map uploads of the web API: per-vertex maps (one file per hemisphere) and MNI152 volumes.

An upload is a map when its file name says so
(:func:`brainpainter.maps.inputs.is_map_input`: ``lh.thickness``, ``.mgh``/``.mgz``,
``.func.gii``, ``.npy``, ``.annot``...) or when it is a NIfTI volume (``.nii``,
``.nii.gz``, 3-D or 4-D, projected onto fsaverage by
:func:`brainpainter.maps.volume.project_volume`) or a CIFTI-2 file (``.dscalar.nii``,
``.dlabel.nii``..., :mod:`brainpainter.maps.cifti`). Two files (lh and rh) travel in
one request body, one after the other, with their names and sizes in the query.

The files are read (:func:`build_bundle`) in a process of its own, started by
:func:`brainpainter.web.upload.read_map_upload` and killed after the server's
parse time limit, with its data memory bounded (:data:`MEMORY_LIMIT`);
compressed files (``.gz``, ``.mgz``) are inflated to disk, at most
:data:`MAX_INFLATED` bytes. What is kept is a *bundle* (:data:`MAGIC`, one JSON
line, then the files): what :func:`brainpainter.maps.inputs.read_maps` read, never
the files as sent (a file inflated to a gigabyte of padding is kept as its
vertex values): one ``.npy`` (gzipped where that pays) of shape (images,
vertices) per hemisphere, and in the header the image names, label names and
colours, a volume's or a CIFTI file's subcortical means and the mesh (fsaverage or
fsLR). Previews and jobs rebuild the maps from it (:func:`read_bundle`) exactly
as the upload read them. Client file names are
only labels: they are made safe (:func:`file_name`) and every file is written
into a fresh private folder. A GIfTI is read with ``external="refuse"``: data it
says is in another file is an error, never read.
"""

from __future__ import annotations

import gzip
import io
from pathlib import Path, PurePosixPath
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.web.bundle import bundle_header as read_header
from brainpainter.web.bundle import members, write_bundle

#: The first bytes of a stored map upload (:data:`KIND`, then the format's version).
MAGIC = b"BRAINPAINTER-MAPS/2\n"
#: The first bytes of a stored map upload of any version (an earlier one reads as damaged).
KIND = b"BRAINPAINTER-MAPS/"
#: NIfTI volumes (one file, MNI152 space), projected onto the cortex.
VOLUME_SUFFIXES = (".nii", ".nii.gz")
#: Compound endings kept when a client's file name is made safe.
_ENDINGS = (".func.gii.gz", ".shape.gii.gz", ".label.gii.gz", ".gii.gz", ".func.gii", ".shape.gii",
            ".label.gii", ".nii.gz")
#: Largest size a compressed file may inflate to (bytes).
MAX_INFLATED = 1 << 30
#: Largest number of voxels of one volume of a NIfTI file (e.g. 512 x 512 x 512).
MAX_VOXELS = 1 << 27
#: Data memory (bytes) of the process that reads a map upload.
MEMORY_LIMIT = 4 << 30


def is_map_upload(names: list[str]) -> bool:
    """Whether an upload of files named `names` is a map (or volume) rather than a region table."""
    from brainpainter.maps.inputs import is_map_input

    return any(is_map_input(n) or n.lower().endswith(VOLUME_SUFFIXES) for n in names)


def is_bundle(data: bytes) -> bool:
    """Whether stored upload bytes are a map bundle (else a table)."""
    return data.startswith(KIND)


def file_name(name: str) -> str:
    """A client's file name made safe for a file in a private folder: no path, no leading dot.

    ``../x/lh.thickness`` -> ``lh.thickness``; ``my map.func.gii`` -> ``my_map.func.gii``.
    """
    from brainpainter.io.output import safe_name

    base = PurePosixPath(name.replace("\\", "/")).name
    lower = base.lower()
    ending = next((e for e in _ENDINGS if lower.endswith(e)), PurePosixPath(base).suffix.lower())
    stem = base[: len(base) - len(ending)] if ending else base
    stem = safe_name(stem).lstrip("._")[:80] or "map"
    return stem + ("".join(ch for ch in ending if ch.isalnum() or ch == ".") if ending else "")


def split_body(data: bytes, names: list[str], sizes: list[int],
               max_files: int = 2) -> list[tuple[str, bytes]]:
    """The files of a request body: `names` with `sizes` bytes each, one after the other.

    Raises
    ------
    BrainPainterError
        When the sizes do not add up to the body, or more than `max_files` files are given
        (a map: two, lh and rh).
    """
    if len(names) > max_files:
        raise BrainPainterError(f"{len(names)} files were sent; a map upload is one file, or two (lh and "
                                "rh). Upload one map (or one volume) at a time.")
    if len(names) == 1 and not sizes:
        return [(names[0], data)]
    if len(sizes) != len(names) or any(s < 0 for s in sizes) or sum(sizes) != len(data):
        raise BrainPainterError(
            f"the body has {len(data)} bytes but the sizes given are {sizes} for files {names}; give one "
            "size per name (size=...), in the order of the files in the body.")
    parts, start = [], 0
    for n, s in zip(names, sizes, strict=True):
        parts.append((n, data[start:start + s]))
        start += s
    return parts


def hemispheres(parts: list[tuple[str, bytes]], hemis: list[str]) -> list[str | None]:
    """The hemisphere of each file: given (``hemi=lh``), else from its name; None for one volume.

    Raises
    ------
    BrainPainterError
        A name that says no hemisphere, or two files of the same hemisphere.
    """
    from brainpainter.maps.inputs import pair_of

    if hemis and len(hemis) != len(parts):
        raise BrainPainterError(f"hemi was given {len(hemis)} time(s) for {len(parts)} file(s); give one "
                                "hemi (lh or rh) per file, or none.")
    out: list[str | None] = []
    for k, (name, _) in enumerate(parts):
        safe = file_name(name)
        if not is_map_upload([safe]):
            raise BrainPainterError(
                f"{safe!r} is not a map file (maps are lh.thickness, .mgh/.mgz, .func.gii, .npy, .annot, "
                ".label.gii, or one .nii/.nii.gz volume); upload one table at a time, or one or two maps.")
        if hemis:
            if hemis[k] not in ("lh", "rh"):
                raise BrainPainterError(f"hemi must be lh or rh; {hemis[k][:20]!r} was given.")
            out.append(hemis[k])
            continue
        if len(parts) == 1 and safe.lower().endswith(VOLUME_SUFFIXES):
            out.append(None)  # a volume, or a per-vertex NIfTI with lh/rh in its name: decided by its shape
            continue
        try:
            found = pair_of(Path("/nonexistent-brainpainter-upload") / safe)
        except BrainPainterError:
            raise BrainPainterError(
                f"cannot tell the hemisphere of {safe!r}: its name has no lh./rh., hemi-L/hemi-R or .L./.R.; "
                "rename the file (e.g. lh." + safe + ") and upload it again.") from None
        out.append(next(h for h, p in found.items() if p.name == safe))
    given = [h for h in out if h is not None]
    if len(set(given)) < len(given):
        raise BrainPainterError(f"both files ({', '.join(file_name(n) for n, _ in parts)}) are the "
                                f"{given[0]} hemisphere; upload one lh and one rh file.")
    return out


# -- reading (in the process that upload.read_map_upload starts) ------------------------------
def inflate(path: Path) -> Path:
    """`path` itself, or for ``.gz``/``.mgz`` its inflated copy beside it (``.nii``/``.mgh``).

    Raises
    ------
    BrainPainterError
        When it inflates to more than :data:`MAX_INFLATED` bytes, or is not gzip.
    """
    name = path.name
    lower = name.lower()
    if lower.endswith(".mgz"):
        out = path.with_name(name[:-4] + ".mgh")
    elif lower.endswith(".gz"):
        out = path.with_name(name[:-3])
    else:
        return path
    total = 0
    try:
        with gzip.open(path, "rb") as src, out.open("wb") as dst:
            while block := src.read(1 << 20):
                total += len(block)
                if total > MAX_INFLATED:
                    raise BrainPainterError(
                        f"{name!r} inflates to more than {MAX_INFLATED >> 20} MB; this server reads at most "
                        "that much. Upload a smaller map.")
                dst.write(block)
    except (OSError, EOFError, gzip.BadGzipFile) as exc:
        from brainpainter.web.disk import disk_full

        if disk_full(exc):  # the server's disk, not the file: the reading process reports it (507)
            raise
        raise BrainPainterError(f"{name!r} is not a readable gzip file ({type(exc).__name__}); upload the "
                                "file as written by your software.") from None
    path.unlink()
    return out


def build_bundle(work: Path, entries: list[tuple[str | None, Path]],
                 max_images: int) -> tuple[dict[str, Any], list[str]]:
    """Read the map files `entries` (hemisphere, path) and write ``work/bundle.bin``.

    Returns
    -------
    (dict, list of str)
        The upload's report (:func:`base_report`) and its image names.
    """
    from brainpainter.maps.cifti import is_cifti

    names = [p.name for _, p in entries]
    files = [(hemi, inflate(p)) for hemi, p in entries]
    if len(files) == 1 and files[0][0] is None:
        path = files[0][1]
        if is_cifti(path):
            return _cifti_bundle(work, path, names[0], max_images)
        shape = _nifti_shape(path)
        if sum(s > 1 for s in shape[:3]) >= 3:
            return _volume_bundle(work, path, names[0], shape, max_images)
        try:  # a per-vertex NIfTI (N x 1 x 1): its hemisphere from its name
            from brainpainter.maps.inputs import pair_of

            files = [(next(iter(pair_of(path))), path)]
        except BrainPainterError:
            raise BrainPainterError(
                f"{names[0]!r} holds one value per vertex (shape {list(shape)}) but its name says no "
                "hemisphere; rename it (e.g. lh." + names[0] + ") and upload it again.") from None
    return _surface_bundle(work, [(str(h), p) for h, p in files], names, max_images)


def _nifti_shape(path: Path) -> tuple[int, ...]:
    import nibabel as nib

    try:
        img = nib.Nifti1Image.from_filename(str(path))  # the header only: the data stay on disk
    except Exception as exc:
        raise BrainPainterError(f"cannot read {path.name!r} as NIfTI ({type(exc).__name__}); upload a .nii "
                                "or .nii.gz volume in MNI152 space.") from None
    return tuple(int(s) for s in img.shape)


def _volume_bundle(work: Path, path: Path, shown: str, shape: tuple[int, ...],
                   max_images: int) -> tuple[dict[str, Any], list[str]]:
    import numpy as np

    from brainpainter.maps.inputs import read_volume
    from brainpainter.maps.volume import load_volume

    volume = load_volume(path)
    n = volume.n_volumes
    if n > max_images:
        raise BrainPainterError(
            f"{shown!r} holds {n} volumes; this server draws at most {max_images} images per upload. Upload "
            "fewer volumes (e.g. split it with fslsplit), or render it with 'brainpainter render' on your "
            "own computer.")
    voxels = int(np.prod(volume.shape[:3]))
    if voxels > MAX_VOXELS:
        raise BrainPainterError(f"{shown!r} has {voxels} voxels per volume; this server reads at most "
                                f"{MAX_VOXELS}. Resample it to 1 or 2 mm MNI152.")
    maps = read_volume(path)  # the cortex by registration fusion, the structures by their means
    report = base_report(maps, "volume", [shown], f"volume: {shown} (MNI152, {'x'.join(map(str, shape))}) "
                         f"projected onto fsaverage, {_images(maps.n_images)}")
    _write_bundle(work, "volume", maps, f"volume={shown}", report, volume=path)
    return report, list(maps.images)


def _cifti_bundle(work: Path, path: Path, shown: str, max_images: int) -> tuple[dict[str, Any], list[str]]:
    """A CIFTI-2 file: its cortex per hemisphere (fsLR or fsaverage) and its subcortical means."""
    from brainpainter.maps.inputs import read_maps

    maps = read_maps(path)
    _check_images(maps, max_images)
    kind = "label map" if maps.categories is not None else "map"
    what = f"{len(maps.categories)} labels" if maps.categories is not None else _images(maps.n_images)
    meshes = ", ".join(sorted({_mesh(maps, v.shape[1]) for v in maps.values.values()}))
    report = base_report(maps, kind, [shown], f"CIFTI {kind}: {shown}, {meshes}, {what}")
    _write_bundle(work, "cifti", maps, f"cifti={shown}", report)
    return report, list(maps.images)


def _check_images(maps: Any, max_images: int) -> None:
    if maps.n_images > max_images:
        raise BrainPainterError(
            f"the map holds {maps.n_images} images; this server draws at most {max_images} images per "
            "upload. Upload fewer images, or render it with 'brainpainter render' on your own computer.")


def _surface_bundle(work: Path, files: list[tuple[str, Path]], names: list[str],
                    max_images: int) -> tuple[dict[str, Any], list[str]]:
    from brainpainter.maps.inputs import read_maps

    order = sorted(files, key=lambda f: f[0])  # lh first
    maps = read_maps({h: p for h, p in order}, external="refuse")  # a GIfTI reads no other file
    _check_images(maps, max_images)
    surfaces = sorted({_mesh(maps, v.shape[1]) for v in maps.values.values()})
    kind = "label map" if maps.categories is not None else "map"
    what = f"{len(maps.categories)} labels" if maps.categories is not None else _images(maps.n_images)
    shown = [n for _, n in sorted(zip([h for h, _ in files], names, strict=True))]
    report = base_report(maps, kind, shown, f"{kind}: {' + '.join(shown)}, {', '.join(surfaces)}, {what}")
    source = ", ".join(f"{h}={n}" for h, n in zip(sorted(h for h, _ in files), shown, strict=True))
    _write_bundle(work, "surface", maps, source, report)
    return report, list(maps.images)


def _mesh(maps: Any, n: int) -> str:
    """The mesh of a map of `n` vertices per hemisphere (``fsaverage5``, ``fsLR 32k``)."""
    from brainpainter.maps.resolution import FSLR, surface_of

    return FSLR[n] if maps.space == "fsLR" else surface_of(n)


def _images(n: int) -> str:
    return f"{n} image{'s' if n != 1 else ''}"


def base_report(maps: Any, kind: str, names: list[str], summary: str) -> dict[str, Any]:
    """The report of a map upload (the page shows ``summary``: what was understood)."""
    import numpy as np

    finite = maps.finite()
    return {
        "ok": True, "kind": "map", "map_kind": kind, "summary": summary, "files": names,
        "hemis": sorted(maps.values),
        "surfaces": {h: _mesh(maps, v.shape[1]) for h, v in maps.values.items()},
        "n_images": maps.n_images, "images": list(maps.images[:20]),
        "categories": None if maps.categories is None else list(maps.categories[:50]),
        "values": {"range": [float(np.min(finite)), float(np.max(finite))] if finite.size else None,
                   "scale": None, "hints": []},
        "notes": [], "errors": [],
    }


def _write_bundle(work: Path, kind: str, maps: Any, source: str, report: dict[str, Any],
                  volume: Path | None = None) -> None:
    """Write ``work/bundle.bin``: the maps as read (:class:`brainpainter.maps.inputs.VertexMaps`), and
    a volume upload's NIfTI file (gzipped), which a figure's slice and glass-brain panels show.

    Each hemisphere's values, ndarray of float32, shape (n_images, n_vertices), as an ``.npy``,
    gzipped where its first megabyte halves (a constant or sparse map stays small; noisy values, which
    would cost seconds to compress for little, stay as they are); image names, label names and
    colours, region values and `source` (the client's file names, never a server path) in the header.
    """
    import numpy as np

    out = work / "out"
    out.mkdir()
    stored = []
    for hemi, values in sorted(maps.values.items()):
        buf = io.BytesIO()
        np.save(buf, np.asarray(values, np.float32), allow_pickle=False)
        raw = buf.getbuffer()
        packed = len(gzip.compress(raw[:1 << 20], compresslevel=1)) < min(len(raw), 1 << 20) // 2
        target = out / (f"{hemi}.npy.gz" if packed else f"{hemi}.npy")
        target.write_bytes(gzip.compress(raw, compresslevel=1) if packed else raw)
        stored.append((hemi, target))
    colors = maps.category_colors
    header = {"kind": kind, "report": report, "images": list(maps.images), "source": source,
              "space": maps.space,
              "categories": None if maps.categories is None else list(maps.categories),
              "category_colors": None if colors is None else np.asarray(colors, float).tolist(),
              "regions": {k: [float(x) for x in v] for k, v in (maps.regions or {}).items()}}
    if volume is not None:
        (out / "volume.nii.gz").write_bytes(gzip.compress(volume.read_bytes(), compresslevel=1))
        stored.append(("volume", out / "volume.nii.gz"))
    write_bundle(work / "bundle.bin", MAGIC, header, "hemi", list(stored))


# -- reading a stored bundle -----------------------------------------------------------------
def bundle_header(data: bytes) -> tuple[dict[str, Any], int]:
    """The JSON header of a bundle and where its files start."""
    return read_header(data, MAGIC, "hemi", ("lh", "rh", "volume"),
                       "the stored map upload is damaged; upload the map again.")


def base_of(data: bytes) -> dict[str, Any]:
    """The report stored with a bundle."""
    report: dict[str, Any] = bundle_header(data)[0]["report"]
    return report


def read_bundle(data: bytes) -> Any:
    """The maps of bundle `data`, as the upload's reader read them (nothing is written to disk).

    Returns
    -------
    brainpainter.maps.inputs.VertexMaps
        ``values`` of shape (n_images, n_vertices) per hemisphere stored, with the stored image
        names, labels and region values.

    Raises
    ------
    BrainPainterError
        The bundle is damaged (one line: upload the map again).
    """
    import numpy as np

    from brainpainter.maps.inputs import VertexMaps

    header, start = bundle_header(data)
    try:
        values = {str(f["hemi"]): np.load(io.BytesIO(gzip.decompress(content) if str(f["name"]).endswith(
            ".gz") else content), allow_pickle=False) for f, content in members(data, header, start)
            if f["hemi"] != "volume"}
        images = tuple(str(i) for i in header["images"])
        if any(v.ndim != 2 or v.shape[0] != len(images) for v in values.values()):
            raise ValueError("shapes")
        colors = header["category_colors"]
        return VertexMaps(
            values, images, None if header["categories"] is None else tuple(header["categories"]),
            None if colors is None else np.asarray(colors, float), str(header["source"]),
            {str(k): np.asarray(v, float) for k, v in header["regions"].items()} or None,
            str(header.get("space") or "fsaverage"))
    except (OSError, EOFError, ValueError, KeyError, TypeError):
        raise BrainPainterError("the stored map upload is damaged; upload the map again.") from None


def bundle_volume(data: bytes) -> Any:
    """The NIfTI volume of a volume upload's bundle `data` (a nibabel image in memory), or None for
    other uploads (a table, surface maps, CIFTI)."""
    import nibabel as nib

    if not is_bundle(data):
        return None
    header, start = bundle_header(data)
    for f, content in members(data, header, start):
        if f["hemi"] == "volume":
            try:
                return nib.Nifti1Image.from_bytes(gzip.decompress(content))
            except (OSError, EOFError, ValueError):
                raise BrainPainterError("the stored volume upload is damaged; upload it again.") from None
    return None


def blob_kwargs(data: bytes, options: Any) -> dict[str, Any]:
    """The run's keywords of a volume upload `data` drawn as blobs (option ``volume_surface``): the
    volume as ``--volume-surface``, its colour bar labelled with the file's name unless ``blobs_label``
    was given, and no map label (the volume is not projected onto the cortex).

    Raises
    ------
    BrainPainterError
        The upload is no volume (a table, surface maps, CIFTI).
    """
    volume = bundle_volume(data)
    if volume is None:
        raise BrainPainterError("option volume_surface draws a volume upload's clusters as blobs; this "
                                "upload is no volume. Upload an MNI152 volume (.nii, .nii.gz), or leave "
                                "volume_surface out.")
    (shown,) = base_of(data)["files"]
    volume.set_filename(shown)  # a label only (the images' name, messages): the data are in memory
    label = options.blobs_label or shown
    return {"volume_surface": volume, "blobs_label": label, "map_label": options.map_label}


def figure_panels(params: Any, data: bytes, blobs: bool = False) -> dict[str, Any]:
    """The slice and glass-brain panels of figure job `params` (``FigureParams``) as
    :func:`brainpainter.media.figure.make_figure` keywords, with the volume of upload `data` (`blobs`: it
    is drawn as blobs, ``--volume-surface``, which the panels show on the blobs' scale)."""
    if not params.slices and not params.projections:
        return {}
    return {"slices": params.slices, "projections": params.projections or None,
            "convention": params.convention, "volume_image": None if blobs else bundle_volume(data)}
