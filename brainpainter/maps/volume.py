"""Volumes onto the surface: an MNI152 (or subject-space) volume sampled at the cortex.

:func:`project_volume` samples a volume in MNI152 space at the MNI152 position of every
fsaverage vertex found by registration fusion (RF-ANTs, Wu et al. 2018; see
:mod:`brainpainter.maps.regfusion`), averaged over the cortical sheet around it (``ribbon``),
along its normal (``line``) or not at all (``point``; :mod:`brainpainter.maps.sheet`), or a
subject-space volume between that subject's white and pial surfaces (:mod:`brainpainter.maps.depth`).
:func:`subcortical_means` gives the mean of the same volume inside each subcortical structure of
the default template, keyed as region tables key them, so one NIfTI colours cortex and subcortex.
:func:`volume_images` is the per-image form the command line uses (``--volume``).

Volumes that cannot be what they are used as are refused with one line
(:class:`~brainpainter.errors.BrainPainterError`): a 2-D image, no spatial transform, absurd
voxel sizes, an extent that does not cover the brain, every voxel 0 or NaN.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.maps import depth as depth_sampling
from brainpainter.maps import sheet
from brainpainter.maps.options import RADIUS_MM, Projection, check_projection
from brainpainter.maps.regfusion import aseg_mni152, fsaverage_mni152
from brainpainter.maps.trilinear import trilinear
from brainpainter.maps.voxel_points import kept_voxel_coordinates, voxel_coordinates

Method = Literal["linear", "nearest"]
ORDERS = {"nearest": 0, "linear": 1}
VOXEL_MM = (0.1, 10.0)          # voxel sizes outside this range cannot be a brain volume
MIN_COVERAGE = 0.5              # share of the cortex the volume's extent must reach
MIN_FINITE_WEIGHT = 0.5         # linear: a point takes a value when finite voxels carry this much weight
ImageLike = str | os.PathLike[str] | Any   # a path, or a nibabel spatial image


@dataclass(frozen=True)
class Volume:
    """A volume as read: its voxels (not yet loaded) and where they are.

    Attributes
    ----------
    name : str
        The file's name without ``.nii.gz`` etc., or ``"volume"`` for an image in memory.
    dataobj : array-like, shape (x, y, z) or (x, y, z, n_volumes)
        nibabel's array proxy (or an array): read one volume at a time.
    affine : ndarray, shape (4, 4)
        Voxel indices to world millimetres.
    """

    name: str
    dataobj: Any
    affine: NDArray[np.float64]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(int(s) for s in self.dataobj.shape)

    @property
    def n_volumes(self) -> int:
        return self.shape[3] if len(self.shape) == 4 else 1

    @property
    def image_names(self) -> tuple[str, ...]:
        """Name of each image: the file's name for a 3-D volume; for a 4-D one, ``"{name}_{index}"``
        per volume, the index from 0, zero-padded (``"bold_000"``)."""
        if len(self.shape) == 3:
            return (self.name,)
        width = len(str(self.n_volumes - 1))
        return tuple(f"{self.name}_{i:0{width}d}" for i in range(self.n_volumes))

    def volume(self, i: int) -> NDArray[np.float32]:
        """Volume `i` as float32, shape (x, y, z)."""
        data = self.dataobj if len(self.shape) == 3 else self.dataobj[..., i]
        return np.asarray(data, dtype=np.float32)


def load_volume(img: ImageLike) -> Volume:
    """Read a volume (path or nibabel image) and refuse what cannot be one.

    Refused: no file, not an image, fewer than three spatial axes of more than one voxel (a 2-D
    image, or a per-vertex map stored as NIfTI ``n x 1 x 1``), more than four axes, an affine that
    is not finite or is singular, voxel sizes outside 0.1-10 mm, NIfTI files without a spatial
    transform (sform and qform codes 0).
    """
    import nibabel as nib

    from brainpainter.io.hdf5 import check_hdf5
    from brainpainter.io.sniff import HEAD, not_a_volume

    name = "volume"
    image: Any = img
    if isinstance(img, (str, os.PathLike)):
        path = Path(img)
        name = _stem(path)
        if not path.is_file():
            raise BrainPainterError(f"volume file {path} does not exist; give a NIfTI (.nii, .nii.gz) "
                                    "or MGH (.mgz) volume in MNI152 space.")
        with path.open("rb") as f:
            found = not_a_volume(f.read(HEAD))
        if found:  # never given to nib.load, which reads a GIfTI (and the files it names)
            raise BrainPainterError(f"volume file {path.name!r} looks like {found}, not a NIfTI or MGH "
                                    "volume; a map per vertex goes to --lh/--rh, a volume is .nii, .nii.gz "
                                    "or .mgz.")
        check_hdf5(path, "volume file")  # MINC-2 can take its data from other files
        try:
            image = nib.load(str(path))
        except Exception as exc:  # nibabel raises ImageFileError, ValueError, OSError, ...
            raise BrainPainterError(f"cannot read {path} as a volume ({type(exc).__name__}: {exc}); "
                                    "give a NIfTI (.nii, .nii.gz) or MGH (.mgz) volume.") from None
    elif not (hasattr(image, "dataobj") and hasattr(image, "affine")):
        raise BrainPainterError(f"a volume must be a file path or a nibabel image; a "
                                f"{type(image).__name__} was given.")
    elif getattr(image, "get_filename", lambda: None)():
        name = _stem(Path(image.get_filename()))
    _check_transform(image, name)
    return Volume(name=name, dataobj=_spatial(image, name), affine=np.asarray(image.affine, dtype=np.float64))


def _stem(path: Path) -> str:
    name = path.name
    for suffix in (".nii.gz", ".nii", ".mgz", ".mgh", ".img", ".hdr"):
        if name.lower().endswith(suffix):
            return name[: -len(suffix)]
    return path.stem


def _spatial(img: Any, name: str) -> Any:
    """The image's data object with trailing length-1 axes after the third dropped."""
    shape = tuple(int(s) for s in img.shape)
    data = img.dataobj
    if len(shape) > 4 and all(s == 1 for s in shape[4:]):
        data, shape = np.asarray(data).reshape(shape[:4]), shape[:4]
    if len(shape) == 4 and shape[3] == 1:
        data, shape = data[..., 0], shape[:3]
    if len(shape) < 3 or sum(s > 1 for s in shape[:3]) < 3:
        if len(shape) >= 3 and shape[0] > 1 and all(s == 1 for s in shape[1:3]):
            hint = "it looks like one value per vertex (FreeSurfer's N x 1 x 1 form): pass it as a map."
        else:
            hint = "give a 3-D volume (or a 4-D series of volumes)."
        raise BrainPainterError(f"{name} has shape {shape}, a 2-D image, not a volume; {hint}")
    if len(shape) > 4:
        raise BrainPainterError(f"{name} has {len(shape)} axes {shape}; a volume has 3, or 4 for a series "
                                "of volumes. Split it into 3-D or 4-D files (e.g. with fslsplit).")
    return data


def _check_transform(img: Any, name: str) -> None:
    affine = np.asarray(img.affine, dtype=np.float64)
    header: Any = getattr(img, "header", None)
    codes = [int(header[k]) for k in ("sform_code", "qform_code")] if _is_nifti(header) else [1]
    if not any(codes):
        raise BrainPainterError(f"{name} has no spatial transform (NIfTI sform and qform codes are 0), so "
                                "where its voxels lie is unknown; give a volume registered to MNI152.")
    if affine.shape != (4, 4) or not np.isfinite(affine).all() or abs(np.linalg.det(affine[:3, :3])) < 1e-9:
        raise BrainPainterError(f"{name} has an affine that does not place its voxels in space (singular "
                                f"or not finite): {affine.tolist()}; give a volume registered to MNI152.")
    sizes = np.linalg.norm(affine[:3, :3], axis=0)
    if sizes.min() < VOXEL_MM[0] or sizes.max() > VOXEL_MM[1]:
        raise BrainPainterError(
            f"{name} has voxels of {np.round(sizes, 3).tolist()} mm; a brain volume has voxels of "
            f"{VOXEL_MM[0]}-{VOXEL_MM[1]} mm. Check its affine (header) or resample it to MNI152.")


def _is_nifti(header: Any) -> bool:
    import nibabel as nib

    return isinstance(header, nib.nifti1.Nifti1Header)


@cache
def _fsaverage_points() -> NDArray[np.float64]:
    """``fsaverage_mni152()`` of both hemispheres stacked, lh first: shape (327684, 3)."""
    points = np.concatenate(list(fsaverage_mni152().values()))
    points.flags.writeable = False
    return points


def _voxel_coordinates(volume: Volume, points: NDArray[np.float64]) -> tuple[NDArray[np.float64],
                                                                             NDArray[np.bool_]]:
    """Voxel coordinates of world points, shape (3, n), and which points lie inside the grid."""
    return voxel_coordinates(volume.affine, volume.shape, points)


def _kept_coordinates(volume: Volume, name: Hashable, points: Callable[[], NDArray[np.float64]]
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """:func:`_voxel_coordinates` of the shipped point set `name` (``points()``), kept per grid."""
    return kept_voxel_coordinates(volume.affine, volume.shape, name, points)


def _check_not_conformed(volume: Volume) -> None:
    """Refuse a FreeSurfer conformed volume (256^3, 1 mm, LIA): a recon-all subject's space, not MNI152."""
    import nibabel as nib

    sizes = np.linalg.norm(volume.affine[:3, :3], axis=0)
    if volume.shape[:3] == (256, 256, 256) and np.allclose(sizes, 1.0) \
            and nib.aff2axcodes(volume.affine) == ("L", "I", "A"):  # type: ignore[no-untyped-call]
        raise BrainPainterError(
            f"{volume.name} is a FreeSurfer conformed volume (256^3, 1 mm, LIA), in the space of a "
            "recon-all subject (or fsaverage's MNI305), not MNI152; give that subject's surfaces "
            "(white={'lh': 'surf/lh.white', ...}, pial={...}) or register the volume to MNI152.")


def _check_coverage(volume: Volume, inside: NDArray[np.bool_], subject: bool) -> None:
    if not subject:
        _check_not_conformed(volume)
    share = float(inside.mean()) if inside.size else 0.0
    if share >= MIN_COVERAGE:
        return
    corners = np.array([[i, j, k, 1] for i in (0, volume.shape[0] - 1) for j in (0, volume.shape[1] - 1)
                        for k in (0, volume.shape[2] - 1)], dtype=np.float64) @ volume.affine.T
    box = f"x {corners[:, 0].min():.0f}..{corners[:, 0].max():.0f}, y {corners[:, 1].min():.0f}.." \
          f"{corners[:, 1].max():.0f}, z {corners[:, 2].min():.0f}..{corners[:, 2].max():.0f} mm"
    if subject:
        raise BrainPainterError(
            f"{volume.name} ({box}) holds only {share:.0%} of the given white/pial surfaces' points; the "
            "surfaces are not those of this volume's subject (FreeSurfer surfaces need the cras of "
            "their volume: give the surf/ files themselves).")
    raise BrainPainterError(
        f"{volume.name} ({box}) covers only {share:.0%} of the cortex in MNI152 space, so it is not an "
        "MNI152 volume. Register it to MNI152 (fMRIPrep, ANTs, FSL), or for a subject-space scan give "
        "that subject's surfaces: project_volume(img, white={'lh': ..., 'rh': ...}, pial={...}).")


def check_mni152(volume: Volume) -> None:
    """Refuse a volume that is not in MNI152 (one line): a FreeSurfer conformed volume, or one whose
    extent holds less than half of the cortex's MNI152 positions (a sample of them is enough)."""
    _, inside = _kept_coordinates(volume, "cortex sample", lambda: _fsaverage_points()[::16])  # enough
    _check_coverage(volume, inside, subject=False)


def _sample(volume: Volume, ijk: NDArray[np.float64], inside: NDArray[np.bool_], order: int
            ) -> NDArray[np.float32]:
    """Every volume at the voxel coordinates: shape (n_volumes, n); NaN outside the grid."""
    from scipy.ndimage import map_coordinates

    out = np.empty((volume.n_volumes, ijk.shape[1]), dtype=np.float32)
    nonzero = False
    data = volume.dataobj
    if volume.n_volumes > 1 and not isinstance(data, np.ndarray) and not _is_uncompressed(data):
        data = np.asarray(data, dtype=np.float32)   # gzip cannot seek: read the series once
    series = Volume(volume.name, data, volume.affine)
    # a series: the interpolation's weights worked out once (a sparse matrix), not once per volume
    matrix = trilinear(volume.shape, ijk) if order == 1 and volume.n_volumes > 1 else None

    def at(grid: NDArray[np.float32]) -> NDArray[np.float32]:
        if matrix is not None:
            values: NDArray[np.float32] = matrix @ grid.ravel(order="F")
            return values
        return map_coordinates(grid, ijk, order=order, mode="nearest", prefilter=False)  # type: ignore[no-any-return]

    done = False
    if matrix is not None and isinstance(data, np.ndarray):
        block = data.reshape(-1, volume.n_volumes, order="F")   # as the matrix ravels (NIfTI's order)
        if np.isfinite(block).all():                     # a series in memory, no NaN: one product
            nonzero, done = bool(np.any(block != 0)), True
            out[:] = (matrix @ block.astype(np.float32, copy=False)).T
    for i in range(0 if done else volume.n_volumes):
        vol = series.volume(i)
        finite = np.isfinite(vol)
        nonzero = nonzero or bool(np.any(finite & (vol != 0)))
        if order == 0 or finite.all():
            out[i] = at(vol)
        else:   # NaN-aware trilinear: the finite voxels around a point, weighted, renormalised
            weight = at(finite.astype(np.float32))
            out[i] = at(np.where(finite, vol, np.float32(0)))
            enough = weight >= MIN_FINITE_WEIGHT
            out[i][enough] /= weight[enough]
            out[i][~enough] = np.nan
    if not nonzero:
        raise BrainPainterError(f"every voxel of {volume.name} is 0 or NaN; there is nothing to draw. "
                                "Check that the right file (or volume of a series) was given.")
    out[:, ~inside] = np.nan
    out[~np.isfinite(out)] = np.nan     # infinite voxels (nearest) are no value either
    return out


def _is_uncompressed(dataobj: Any) -> bool:
    file_like = getattr(dataobj, "file_like", None)
    return isinstance(file_like, str) and not file_like.lower().endswith((".gz", ".mgz", ".bz2", ".zst"))


def _layout(samples: NDArray[np.float32], four_d: bool) -> NDArray[np.float32]:
    return samples if four_d else samples[0]


def project_volume(img: ImageLike, *, method: Method = "linear", projection: Projection | None = None,
                   radius: float = RADIUS_MM,
                   white: dict[str, depth_sampling.SurfaceLike] | None = None,
                   pial: dict[str, depth_sampling.SurfaceLike] | None = None,
                   depth: depth_sampling.Depth = "mean", n_depths: int = 6) -> dict[str, NDArray[np.float32]]:
    """Sample a volume at the cortex: one value per surface vertex.

    Parameters
    ----------
    img : path or nibabel image
        A NIfTI (``.nii``, ``.nii.gz``) or MGH (``.mgz``) volume, shape (x, y, z) or (x, y, z,
        n_volumes); without `white` and `pial`, in MNI152 (ICBM 2009c, FSL's MNI152, SPM's).
    method : {"linear", "nearest"}
        Trilinear interpolation (statistical maps, probabilities), or the nearest voxel (label
        volumes: values are never mixed).
    projection : {"ribbon", "line", "point"}, optional
        Around each registration-fusion position: ``ribbon`` (default) the mean over the grey-matter
        ribbon within `radius` mm; ``line`` of 10 samples along the normal, ``-radius`` to ``+radius``
        (nilearn's ``vol_to_surf``); ``point`` the position alone (the only one for ``nearest``).
    radius : float
        Millimetres, 0.5-10 (:mod:`brainpainter.maps.sheet`).
    white, pial : dict, optional
        A subject's own surfaces, ``{"lh": ..., "rh": ...}`` (either or both hemispheres; nilearn's
        ``"left"``/``"right"`` also), each a FreeSurfer surface file, a GIfTI ``.surf.gii``, or
        vertex positions, shape (n, 3), in the volume's world millimetres. Then `img` is that
        subject's volume and is sampled at `n_depths` points from white to pial.
    depth : {"mean", "max", "nearest"}
        How the depths combine (with `white`/`pial` only): their mean, their maximum, or the most
        frequent nearest-voxel value (label volumes; implies ``method="nearest"``).
    n_depths : int
        Points per vertex between white (depth 0) and pial (depth 1), ends included.

    Returns
    -------
    dict
        ``{"lh": ndarray (163842,), "rh": ndarray (163842,)}`` of float32: fsaverage's vertices
        (the first 10242 are fsaverage5's, and so on). For a 4-D image each is
        ``(n_volumes, 163842)``. With `white`/`pial`, the hemispheres given, shape (n_vertices,)
        or (n_volumes, n_vertices). NaN where a vertex falls outside the volume or among NaN voxels
        (linear interpolation uses the finite voxels around a vertex when they carry at least half
        of its weight, so a NaN-masked statistical map keeps its values up to the mask's edge).

    Raises
    ------
    BrainPainterError
        A 2-D image, no spatial transform, absurd voxel sizes, less than half of the cortex covered
        (not MNI152, or another subject's surfaces), a FreeSurfer conformed volume without surfaces,
        every voxel 0 or NaN; a projection or radius not allowed.

    Examples
    --------
    >>> maps = brainpainter.project_volume("zstat1_mni.nii.gz")     # doctest: +SKIP
    >>> maps["lh"].shape
    (163842,)
    """
    if method not in ORDERS:
        raise choice_error("method", method, ORDERS)
    projection = check_projection(projection, method, radius)
    if (white is None) != (pial is None):
        raise BrainPainterError("depth sampling needs both white and pial surfaces; only "
                                f"{'white' if pial is None else 'pial'} was given.")
    volume = load_volume(img)
    points, counts = _where(white, pial, depth, n_depths)
    method = "nearest" if white is not None and depth == "nearest" else method
    ijk, inside = (_kept_coordinates(volume, "cortex", _fsaverage_points) if white is None
                   else _voxel_coordinates(volume, np.concatenate(list(points.values()))))
    _check_coverage(volume, inside, subject=white is not None)
    if white is None and projection != "point":
        return _project_depths(volume, projection, float(radius), ORDERS[method])
    samples = _sample(volume, ijk, inside, ORDERS[method])
    out: dict[str, NDArray[np.float32]] = {}
    start = 0
    for hemi, (n, k) in counts.items():
        part = samples[:, start:start + n * k]
        start += n * k
        if k > 1 or white is not None:
            per_depth = part.reshape(volume.n_volumes, k, n)
            part = np.stack([depth_sampling.combine(s, depth) for s in per_depth])
        out[hemi] = _layout(part, len(volume.shape) == 4)
    return out


def _where(white: dict[str, Any] | None, pial: dict[str, Any] | None, depth: str,
           n_depths: int) -> tuple[dict[str, NDArray[np.float64]], dict[str, tuple[int, int]]]:
    """The points :func:`project_volume` samples per hemisphere, shape (n * k, 3), and (n, k): the
    registration-fusion positions (k = 1), or `n_depths` points from a subject's white to pial."""
    if white is None or pial is None:
        return fsaverage_mni152(), {hemi: (len(xyz), 1) for hemi, xyz in fsaverage_mni152().items()}
    return depth_sampling.sample_points(white, pial, depth, n_depths)


def _project_depths(volume: Volume, projection: str, radius: float,
                    order: int) -> dict[str, NDArray[np.float32]]:
    """Each fsaverage vertex's mean of the finite samples at the depths of `projection` along its
    normal (:func:`brainpainter.maps.sheet.depths`); over the sheet within `radius` for ``ribbon``."""
    offsets = sheet.depths(projection, radius)
    ijk, inside = _kept_coordinates(volume, ("along normals", offsets.tobytes()), lambda: np.concatenate(
        [sheet.along_normals(hemi, offsets).reshape(-1, 3) for hemi in ("lh", "rh")]))
    samples = _sample(volume, ijk, inside, order).reshape(volume.n_volumes, 2, len(offsets), -1)
    out: dict[str, NDArray[np.float32]] = {}
    for i, hemi in enumerate(("lh", "rh")):
        mean = np.stack([depth_sampling.combine(s, "mean") for s in samples[:, i]])
        if projection == "ribbon":
            mean = sheet.sheet_mean(mean, hemi, radius)
        out[hemi] = _layout(mean, len(volume.shape) == 4)
    return out


def subcortical_means(img: ImageLike, *, method: Method = "linear") -> dict[str, float | NDArray[np.float64]]:
    """Mean of an MNI152 volume inside each subcortical structure of the default template.

    The structures are fsaverage's aseg (those the glass-brain views draw), placed in MNI152 by
    FreeSurfer's MNI305 -> MNI152 transform; the volume is sampled at the centre of each of their
    1 mm voxels (`method`) and the finite samples are averaged.

    Parameters
    ----------
    img : path or nibabel image
        An MNI152 volume, shape (x, y, z) or (x, y, z, n_volumes).
    method : {"linear", "nearest"}
        How the volume is sampled at the structures' voxels.

    Returns
    -------
    dict
        ``{"Left-Hippocampus": mean, "Brain-Stem": mean, ...}`` keyed as the atlases' subcortical
        regions: a float for a 3-D image, an ndarray (n_volumes,) for a 4-D one. NaN for a
        structure the volume does not reach.
    """
    if method not in ORDERS:
        raise choice_error("method", method, ORDERS)
    volume = load_volume(img)
    points, structure, names = aseg_mni152()
    ijk, inside = _kept_coordinates(volume, "structures", lambda: points)
    check_mni152(volume)
    samples = _sample(volume, ijk, inside, ORDERS[method])
    finite = np.isfinite(samples)
    n = len(names)
    means = np.empty((volume.n_volumes, n))
    for i in range(volume.n_volumes):
        count = np.bincount(structure, weights=finite[i], minlength=n)
        total = np.bincount(structure, weights=np.where(finite[i], samples[i], 0.0), minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            means[i] = np.where(count > 0, total / count, np.nan)
    if len(volume.shape) == 3:
        return {name: float(means[0, k]) for k, name in enumerate(names)}
    return {name: means[:, k].copy() for k, name in enumerate(names)}


#: File endings that may hold a volume (``.mgz``/``.mgh`` and NIfTI also hold per-vertex maps,
#: ``n x 1 x 1``: the header's shape tells them apart).
VOLUME_SUFFIXES = (".nii", ".nii.gz", ".mgz", ".mgh")


def is_volume(data: Any) -> bool:
    """Whether `data` is a volume (a NIfTI/MGH file or nibabel image with two or more spatial
    axes of more than one voxel) rather than a per-vertex map stored in the same format."""
    import nibabel as nib

    image: Any = data
    if isinstance(data, (str, os.PathLike)):
        path = Path(data)
        if not path.name.lower().endswith(VOLUME_SUFFIXES) or not path.is_file():
            return False
        try:
            if path.name.lower().endswith(".mgh"):  # its header only: nib.load leaves an .mgh file open
                with path.open("rb") as f:
                    header = nib.freesurfer.mghformat.MGHHeader.from_fileobj(f)  # type: ignore[no-untyped-call]
                    return _solid(tuple(header.get_data_shape()))
            image = nib.load(str(path))
        except Exception:  # not readable: the map readers say why
            return False
    if not (hasattr(image, "dataobj") and hasattr(image, "affine") and hasattr(image, "shape")):
        return False
    return _solid(tuple(image.shape))


def _solid(shape: tuple[int, ...]) -> bool:
    """Whether an image of `shape` has two or more spatial axes of more than one voxel."""
    return sum(int(s) > 1 for s in tuple(shape)[:3]) >= 2

