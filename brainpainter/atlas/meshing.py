"""Meshes of label volumes: one closed, smooth surface per label (the subcortical pipeline).

For each label: the voxels with that label (islands under `min_island`
voxels dropped) are blurred with a Gaussian of :data:`BLUR_VOXELS` (when the
blurred mask still keeps :data:`BLUR_KEEP` of the voxels in as many pieces:
not for thin structures such as the inferior lateral ventricle), meshed by
marching cubes at level 0.5, smoothed with Taubin's non-shrinking filter,
decimated with MeshLab's quadric edge collapse, and offset along their
normals so that the enclosed volume equals the voxel volume (smoothing and
decimation of thin structures otherwise lose a few per cent). Decimation can
fold a thin part through another: a mesh with self-intersecting faces is made
again with less decimation (:data:`DECIMATION_FRACTIONS`). The blur fills the
one-voxel pits and clefts of a 1 mm segmentation (the cerebellar cortex's
folia), which Taubin smoothing alone leaves as a pitted surface. Vertices are
mapped from voxel indices ``(i, j, k)`` (marching cubes returns them in
array-axis order) to millimetres with the volume's ``vox2ras``; the triangle
winding is flipped when that map is a reflection so that normals point
outwards.

Used by volumetric user atlases (:mod:`brainpainter.atlas.volumes`) and by the
template builder (``tools/brainpainter_builder/subcortical.py``, the aseg
structures). Needs the ``builder`` extra (pymeshlab, scikit-image).
"""

from __future__ import annotations

import ctypes
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.atlas.model import Region
from brainpainter.errors import BrainPainterError

#: Gaussian blur (sigma, voxels) of a structure's mask before marching cubes.
BLUR_VOXELS = 1.0
#: Decimation fractions tried, in order after the asked one, until a mesh has no self-intersection.
DECIMATION_FRACTIONS = (0.35, 0.4, 0.5, 0.7)
#: A structure is blurred only if the blurred mask keeps this fraction of its voxels.
BLUR_KEEP = 0.9
BUILDER_HINT = 'pip install "brainpainter[builder]"'


# -- pymeshlab -------------------------------------------------------------------------
# Why the embree preload is needed (checked again in session 3: without it,
# ``import pymeshlab; import bpy`` fails with "undefined symbol:
# rtcGetSceneTraversable"): pymeshlab and bpy both ship a ``libembree4.so.4``,
# pymeshlab's older. Whichever loads first is reused by the dynamic loader for
# the other (same soname), and bpy needs the newer one. Loading bpy's copy
# first, by path and globally (without importing bpy), lets both work in one
# process, so a notebook or test session can build a template or volume atlas
# and then render it. The alternative, a subprocess per MeshLab call, would
# copy every mesh twice; no MeshLab filter used here needs embree itself.
def _preload_bpy_embree() -> None:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        return
    for folder in spec.submodule_search_locations:
        for lib in sorted(Path(folder, "lib").glob("libembree4.so*")):
            try:
                ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
                return
            except OSError:
                continue


def import_pymeshlab() -> ModuleType:
    """Return the pymeshlab module, loaded so that ``import bpy`` still works afterwards."""
    _preload_bpy_embree()
    try:
        import pymeshlab
    except ImportError as exc:
        raise BrainPainterError(f"meshing needs pymeshlab ({exc}); install it with {BUILDER_HINT}") from None
    module: ModuleType = pymeshlab
    return module


def self_intersecting_faces(vertices: NDArray[Any], faces: NDArray[Any]) -> NDArray[Any]:
    """Faces that intersect another face of the same mesh (MeshLab), shape (n_faces,) of bool.

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (m, 3)
    """
    pymeshlab = import_pymeshlab()
    faces = np.asarray(faces)
    if len(faces) == 0:
        return np.zeros(0, dtype=bool)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(vertices, dtype=np.float64),
                               face_matrix=faces.astype(np.int32)))
    ms.compute_selection_by_self_intersections_per_face()
    mesh = ms.current_mesh()
    if mesh.face_number() != len(faces):  # MeshLab never removes faces here; checked anyway
        raise BrainPainterError("self-intersection test changed the mesh")
    return np.asarray(mesh.face_selection_array(), dtype=bool)


def count_self_intersections(vertices: NDArray[Any], faces: NDArray[Any]) -> int:
    """Number of faces that intersect another face of the same mesh."""
    return int(np.count_nonzero(self_intersecting_faces(vertices, faces)))


def edge_use_counts(faces: NDArray[Any]) -> NDArray[Any]:
    """How many faces use each undirected edge, shape (n_edges,).

    Parameters
    ----------
    faces : ndarray of int, shape (m, 3)
    """
    faces = np.asarray(faces, dtype=np.int64)
    if len(faces) == 0:
        return np.zeros(0, dtype=np.int64)
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keys = edges[:, 0] * (int(faces.max()) + 1) + edges[:, 1]
    counts: NDArray[np.int64] = np.unique(keys, return_counts=True)[1]
    return counts


# -- one mask -> one mesh ---------------------------------------------------------------
@dataclass(frozen=True)
class Structure:
    """One meshed structure.

    Attributes
    ----------
    name : str
        FreeSurfer LUT name (``"Left-Hippocampus"``).
    index : int
        FreeSurfer LUT index (17).
    vertices : ndarray of float64, shape (n, 3)
        tkr-RAS millimetres.
    faces : ndarray of int64, shape (m, 3)
    n_voxels : int
    volume_mm3 : float
        Volume enclosed by the mesh.
    voxel_volume_mm3 : float
        Voxel count times voxel volume.
    smoothed_volume_mm3 : float
        Mesh volume after smoothing and decimation, before the volume match.
    watertight : bool
    blur : float
        Gaussian blur of the mask before meshing, voxels (0: none).
    self_intersections : tuple of int
        Self-intersecting faces at the asked decimation, and in the mesh kept
        (decimated less where the first one crossed itself).
    """

    name: str
    index: int
    vertices: NDArray[Any]
    faces: NDArray[Any]
    n_voxels: int
    volume_mm3: float
    voxel_volume_mm3: float
    smoothed_volume_mm3: float
    watertight: bool
    blur: float = 0.0
    self_intersections: tuple[int, int] = (0, 0)


def _signed_volume(vertices: NDArray[Any], faces: NDArray[Any]) -> float:
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def surface_area(vertices: NDArray[Any], faces: NDArray[Any]) -> float:
    """Total area of a triangle mesh (mm^2 for mm vertices)."""
    fn = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]],
                  vertices[faces[:, 2]] - vertices[faces[:, 0]])
    return 0.5 * float(np.linalg.norm(fn, axis=1).sum())


def _match_volume(vertices: NDArray[Any], faces: NDArray[Any], target: float,
                  steps: int = 3) -> NDArray[Any]:
    """Offset vertices along their normals until the enclosed volume is `target`."""
    for _ in range(steps):
        volume = _signed_volume(vertices, faces)
        normals, area = vertex_normals(vertices, faces, np.float64), surface_area(vertices, faces)
        if area <= 0 or abs(volume - target) <= 1e-4 * target:
            break
        vertices = vertices + normals * ((target - volume) / area)
    return vertices


def _meshing_libraries() -> tuple[ModuleType, ModuleType, Callable[..., Any]]:
    """pymeshlab, trimesh and scikit-image's ``marching_cubes`` (the ``builder`` extra)."""
    pymeshlab = import_pymeshlab()
    import trimesh

    try:
        from skimage.measure import marching_cubes
    except ImportError as exc:
        raise BrainPainterError(
            f"meshing needs scikit-image ({exc}); install it with {BUILDER_HINT}") from None
    return pymeshlab, trimesh, marching_cubes


def mesh_mask(mask: NDArray[Any], vox2ras: NDArray[Any], *, smooth_iterations: int = 30,
              target_fraction: float = 0.3, min_faces: int = 400,
              voxel_volume: float | None = None,
              blur: float = 0.0) -> tuple[NDArray[Any], NDArray[Any], float]:
    """Closed, smooth surface of a binary voxel mask in world coordinates.

    Parameters
    ----------
    mask : ndarray of bool, shape (ni, nj, nk)
    vox2ras : ndarray, shape (4, 4)
        Voxel index to millimetres.
    smooth_iterations : int
        Taubin passes (lambda 0.5, mu -0.53).
    target_fraction : float
        Faces kept by decimation (fraction of the marching-cubes faces).
    min_faces : int
        Never decimate below this many faces.
    voxel_volume : float, optional
        mm^3 per voxel; default ``|det(vox2ras[:3, :3])|``.
    blur : float
        Gaussian blur (sigma, voxels) of the mask before marching cubes; 0 for none.

    Returns
    -------
    vertices : ndarray of float64, shape (n, 3)
    faces : ndarray of int64, shape (m, 3)
        Outward-facing (counter-clockwise seen from outside).
    smoothed_volume : float
        Volume after smoothing and decimation, before the final volume match.
    """
    pymeshlab, trimesh, marching_cubes = _meshing_libraries()

    mask = np.asarray(mask, dtype=bool)
    idx = np.argwhere(mask)
    pad = 2 + int(np.ceil(3 * blur))
    lo = idx.min(axis=0) - pad
    hi = idx.max(axis=0) + pad + 1
    sub = np.zeros(tuple(hi - lo), dtype=np.float32)
    inner = mask[tuple(slice(max(a, 0), b) for a, b in zip(lo, hi, strict=True))]
    off = np.maximum(-lo, 0)
    sub[tuple(slice(o, o + s) for o, s in zip(off, inner.shape, strict=True))] = inner
    if blur > 0:
        from scipy import ndimage

        sub = ndimage.gaussian_filter(sub, blur)
    verts, faces, _, _ = marching_cubes(sub, level=0.5, method="lewiner", allow_degenerate=False)
    verts = verts.astype(np.float64) + lo  # voxel indices (i, j, k) of the full volume
    tm = trimesh.Trimesh(verts, faces, process=True)
    trimesh.smoothing.filter_taubin(tm, lamb=0.5, nu=0.53, iterations=smooth_iterations)
    verts = np.asarray(tm.vertices, dtype=np.float64)
    faces = np.asarray(tm.faces, dtype=np.int64)
    target = max(min_faces, round(len(faces) * target_fraction))
    if target < len(faces):
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=verts, face_matrix=faces.astype(np.int32)))
        ms.meshing_decimation_quadric_edge_collapse(
            targetfacenum=target, optimalplacement=True, preservenormal=True,
            preservetopology=True, planarquadric=True, qualitythr=0.5, autoclean=True)
        mesh = ms.current_mesh()
        if not mesh.is_compact():
            mesh.compact()
        verts = np.asarray(mesh.vertex_matrix(), dtype=np.float64)
        faces = np.asarray(mesh.face_matrix(), dtype=np.int64)
    vox2ras = np.asarray(vox2ras, dtype=np.float64)
    verts = verts @ vox2ras[:3, :3].T + vox2ras[:3, 3]
    if np.linalg.det(vox2ras[:3, :3]) < 0:
        faces = faces[:, ::-1]
    if _signed_volume(verts, faces) < 0:  # marching cubes gave inward faces
        faces = faces[:, ::-1]
    if voxel_volume is None:
        voxel_volume = abs(float(np.linalg.det(vox2ras[:3, :3])))
    smoothed_volume = _signed_volume(verts, faces)
    verts = _match_volume(verts, faces, float(mask.sum()) * voxel_volume)
    return verts, np.ascontiguousarray(faces), smoothed_volume


# -- every label of a volume ------------------------------------------------------------
def build_structures(aseg: NDArray[Any], vox2ras: NDArray[Any], voxel_volume: float,
                     regions: tuple[Region, ...], *, min_island: int = 8,
                     target_fraction: float = 0.3, progress: Callable[[str], None] | None = None,
                     source: str = "mri/aseg.mgz") -> list[Structure]:
    """Mesh every structure of a label volume's look-up table `regions` (the aseg's, or any volume's).

    Parameters
    ----------
    aseg : ndarray of int, shape (ni, nj, nk)
    vox2ras : ndarray, shape (4, 4)
        ``vox2ras_tkr`` of the volume.
    voxel_volume : float
        mm^3 per voxel.
    regions : tuple of Region
        Structures to mesh (``Region.index`` is the label in `aseg`).
    min_island : int
        Connected pieces (26-connectivity) smaller than this many voxels are
        dropped (single stray voxels would show as specks).
    progress : callable, optional
        Called with each structure's name before it is meshed.
    source : str
        Name of the volume, for the error message.
    """
    from scipy import ndimage

    bbox = ndimage.find_objects(np.maximum(aseg, 0), max_label=max(r.index for r in regions))
    missing = [r.key for r in regions if r.index < 1 or bbox[r.index - 1] is None]
    if missing:
        raise BrainPainterError(
            f"{source} has no voxels for {missing}; expected all of the structures in "
            "its look-up table (aseg.tsv: FreeSurferColorLUT indices, as recon-all's aseg has them)"
        )
    out = []
    for region in regions:
        if progress is not None:
            progress(region.key)
        box = bbox[region.index - 1]
        pad = tuple(slice(max(s.start - 1, 0), s.stop + 1) for s in box)
        mask = aseg[pad] == region.index
        n_voxels = int(mask.sum())
        pieces, n = ndimage.label(mask, structure=np.ones((3, 3, 3), dtype=bool))
        if n > 1:
            sizes = np.bincount(pieces.ravel())
            keep = sizes >= min(min_island, int(sizes[1:].max()))
            keep[0] = False
            mask = keep[pieces]
        shift = np.eye(4)
        shift[:3, 3] = [s.start for s in pad]
        blur = blur_for(mask)
        # Decimation can fold a thin part through another; keep more faces until nothing crosses.
        first: int | None = None
        crossing = 0
        for fraction in (*(f for f in DECIMATION_FRACTIONS if f > target_fraction), 1.0):
            verts, faces, smoothed = mesh_mask(mask, vox2ras @ shift, target_fraction=min(
                target_fraction if first is None else fraction, 1.0), voxel_volume=voxel_volume, blur=blur)
            crossing = count_self_intersections(verts, faces)
            first = crossing if first is None else first
            if crossing == 0:
                break
        counts = edge_use_counts(faces)
        out.append(Structure(
            name=region.key, index=region.index, vertices=verts, faces=faces,
            n_voxels=n_voxels, volume_mm3=_signed_volume(verts, faces),
            voxel_volume_mm3=n_voxels * voxel_volume,
            smoothed_volume_mm3=smoothed,
            watertight=bool(len(counts) and np.all(counts == 2)),
            blur=blur, self_intersections=(crossing if first is None else first, crossing),
        ))
    return out


def blur_for(mask: NDArray[Any], sigma: float = BLUR_VOXELS, keep: float = BLUR_KEEP) -> float:
    """`sigma` if blurring `mask` keeps `keep` of its voxels in as many pieces, else 0.

    Thin structures (the inferior lateral ventricle) would shrink or break
    apart at level 0.5 of a blurred mask; they are meshed unblurred.
    """
    from scipy import ndimage

    mask = np.pad(np.asarray(mask, dtype=bool), int(np.ceil(3 * sigma)) + 1)
    blurred = ndimage.gaussian_filter(mask.astype(np.float32), sigma) >= 0.5
    n_before = ndimage.label(mask, structure=np.ones((3, 3, 3), dtype=bool))[1]
    n_after = ndimage.label(blurred, structure=np.ones((3, 3, 3), dtype=bool))[1]
    kept = np.count_nonzero(blurred & mask) / max(np.count_nonzero(mask), 1)
    return float(sigma) if kept >= keep and n_after <= n_before else 0.0


def merge_structures(structures: list[Structure]) -> dict[str, NDArray[Any]]:
    """Concatenate structures into the ``subcortical.npz`` arrays.

    Returns
    -------
    dict with ``vertices`` float32 (n, 3), ``faces`` int32 (m, 3) and
    ``face_label`` int16 (m,) (index into `structures`).
    """
    verts, faces, labels = [], [], []
    base = 0
    for i, s in enumerate(structures):
        verts.append(s.vertices)
        faces.append(s.faces + base)
        labels.append(np.full(len(s.faces), i, dtype=np.int16))
        base += len(s.vertices)
    return {
        "vertices": np.concatenate(verts).astype(np.float32),
        "faces": np.concatenate(faces).astype(np.int32),
        "face_label": np.concatenate(labels),
    }
