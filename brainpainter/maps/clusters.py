"""A volume's supra-threshold clusters as smooth closed surfaces (``--volume-surface``, "blobs").

:func:`find_blobs` reads an MNI152 volume, finds its clusters above ``threshold`` of each sign
(26-connected voxels, :func:`scipy.ndimage.label`, as FSL's ``cluster`` counts them), drops those
smaller than ``min_cluster_mm3``, and turns each into an isosurface at the threshold
(:func:`skimage.measure.marching_cubes` on the voxels, mapped to MNI152 millimetres by the
volume's affine), smoothed without shrinking (Taubin's filter, :func:`trimesh.smoothing.filter_taubin`).
Each vertex carries the volume's value just inside the surface (the largest ``|value|`` along its
inward normal within :data:`DEPTH_MM`): on the isosurface itself every value is the threshold.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.maps.volume import ImageLike, check_mni152, load_volume

#: Depths inside a blob's surface (mm) at which its vertex values are sampled (the largest |value| wins).
DEPTH_MM = (0.5, 1.0, 2.0, 3.0)
#: Taubin smoothing: passes, and the shrinking / inflating steps (lambda, -mu).
TAUBIN = (10, 0.5, 0.53)
#: Palette levels a blob's values are drawn with (its values rounded to the nearest of them).
N_LEVELS = 256


@dataclass(frozen=True)
class Cluster:
    """One cluster: its sign, peak and extent (MNI152 millimetres).

    Attributes
    ----------
    sign : {1, -1}
    peak : float
        Its most extreme value (signed).
    peak_mni : tuple of float, shape (3,)
        Where the peak voxel lies.
    centre : tuple of float, shape (3,)
        Centre of the volume its surface encloses.
    volume_mm3 : float
        Volume its surface encloses.
    voxels_mm3 : float
        Its voxels' volume (voxel count times voxel size).
    """

    sign: int
    peak: float
    peak_mni: tuple[float, float, float]
    centre: tuple[float, float, float]
    volume_mm3: float
    voxels_mm3: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (the manifest's ``blobs.clusters``)."""
        return {"sign": self.sign, "peak": round(self.peak, 4),
                "peak_mni": [round(x, 2) for x in self.peak_mni],
                "centre_mni": [round(x, 2) for x in self.centre],
                "volume_mm3": round(self.volume_mm3, 1), "voxels_mm3": round(self.voxels_mm3, 1)}


@dataclass(frozen=True)
class Blobs:
    """A volume's clusters as one surface mesh, in MNI152 millimetres.

    Attributes
    ----------
    source : str
        The volume's name.
    threshold : float
    min_cluster_mm3 : float
    vertices : ndarray of float64, shape (n_vertices, 3)
    triangles : ndarray of int64, shape (n_triangles, 3)
        Counter-clockwise seen from outside.
    values : ndarray of float64, shape (n_vertices,)
        The volume's value just inside the surface at each vertex (signed).
    clusters : tuple of Cluster
        Largest first.
    """

    source: str
    threshold: float
    min_cluster_mm3: float
    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    values: NDArray[np.float64]
    clusters: tuple[Cluster, ...]

    def digest(self) -> str:
        """A SHA-256 of the surfaces and their values: equal blobs, equal digests (a cached painter's key)."""
        import hashlib

        return hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in (
            self.vertices, self.triangles, self.values))).hexdigest()

    @property
    def levels(self) -> NDArray[np.float64]:
        """The values the palette's blob slots stand for, shape (:data:`N_LEVELS`,), lowest to highest."""
        return np.linspace(float(self.values.min()), float(self.values.max()), N_LEVELS)

    def level_of(self) -> NDArray[np.int64]:
        """Each vertex's level (index into :attr:`levels`), shape (n_vertices,)."""
        lo, hi = float(self.values.min()), float(self.values.max())
        if hi <= lo:
            return np.zeros(len(self.values), np.int64)
        level: NDArray[np.int64] = np.rint((self.values - lo) / (hi - lo) * (N_LEVELS - 1)).astype(np.int64)
        return level

    def summary(self) -> dict[str, Any]:
        """The manifest's ``blobs``: the volume, threshold and each cluster."""
        return {"source": self.source, "threshold": self.threshold, "min_cluster_mm3": self.min_cluster_mm3,
                "clusters": [c.to_dict() for c in self.clusters]}


def find_blobs(img: ImageLike, threshold: float | None, min_cluster_mm3: float = 0.0) -> Blobs:
    """The clusters of an MNI152 volume with ``|value| >= threshold``, as surfaces (module docstring).

    Parameters
    ----------
    img : path or nibabel image
        A 3-D MNI152 volume (a 4-D one of one volume).
    threshold : float
        > 0; clusters of both signs are found.
    min_cluster_mm3 : float
        Clusters of fewer cubic millimetres (of voxels) are dropped.

    Raises
    ------
    BrainPainterError
        No threshold, a volume not in MNI152 space or of several volumes, a threshold at or above
        its largest ``|value|``, no cluster left.
    """
    volume = load_volume(img)
    name = volume.name
    if threshold is None or not threshold > 0:
        given = "none was given" if threshold is None else f"{threshold!r} was given"
        raise BrainPainterError(f"--volume-surface {name} draws the clusters above --threshold; give "
                                f"--threshold T > 0 (e.g. 2.3 for a z-map); {given}.")
    if volume.n_volumes != 1:
        raise BrainPainterError(f"--volume-surface draws one 3-D volume; {name} has {volume.n_volumes} "
                                "volumes. Give one of them (fslroi, nilearn.image.index_img).")
    check_mni152(volume)
    data = np.nan_to_num(np.asarray(volume.volume(0), dtype=np.float64), nan=0.0)
    top = float(np.abs(data).max())
    if threshold >= top:
        raise BrainPainterError(f"--threshold {threshold:g} is at or above the largest |value| of {name} "
                                f"({top:g}), so no voxel is above it; give a threshold below {top:g}.")
    voxel_mm3 = float(abs(np.linalg.det(volume.affine[:3, :3])))
    parts: list[tuple[NDArray[Any], ...]] = []
    clusters: list[Cluster] = []
    found: list[float] = []
    for sign in (1, -1):
        for part, cluster in _sign_clusters(sign, sign * data, volume.affine, float(threshold), voxel_mm3,
                                            min_cluster_mm3, found):
            parts.append(part)
            clusters.append(cluster)
    if not parts:
        raise BrainPainterError(
            f"no cluster of {name} above --threshold {threshold:g} is --min-cluster-mm3 "
            f"{min_cluster_mm3:g} "
            f"or larger (the largest is {max(found, default=0):.0f} mm3); give a smaller --min-cluster-mm3.")
    order = np.argsort([-c.voxels_mm3 for c in clusters], kind="stable")
    offsets = np.cumsum([0] + [len(parts[i][0]) for i in order])
    vertices = np.concatenate([parts[i][0] for i in order])
    triangles = np.concatenate([parts[i][1] + offsets[k] for k, i in enumerate(order)])
    values = np.concatenate([parts[i][2] for i in order])
    return Blobs(name, float(threshold), float(min_cluster_mm3), vertices, triangles.astype(np.int64), values,
                 tuple(clusters[i] for i in order))


def _sign_clusters(sign: int, data: NDArray[np.float64], affine: NDArray[np.float64], threshold: float,
                   voxel_mm3: float, min_mm3: float,
                   found: list[float]) -> list[tuple[tuple[NDArray[Any], ...], Cluster]]:
    """The clusters of one `sign` (`data`: the volume times it): ``((vertices, triangles, values), Cluster)``.

    `found` collects every cluster's size (mm3), kept or not.
    """
    from scipy import ndimage

    mask = data >= threshold
    labels, _ = ndimage.label(mask, structure=np.ones((3, 3, 3), bool))
    out: list[tuple[tuple[NDArray[Any], ...], Cluster]] = []
    for k, where in enumerate(ndimage.find_objects(labels), start=1):
        if where is None:
            continue
        own = labels[where] == k
        size = float(own.sum()) * voxel_mm3
        found.append(size)
        if size < min_mm3:
            continue
        # the cluster's box and one voxel around it, the volume's own values (those of other clusters:
        # 0), padded with 0 < threshold so that a cluster at the volume's edge closes too
        box = tuple(slice(max(s.start - 1, 0), min(s.stop + 1, n))
                    for s, n in zip(where, data.shape, strict=True))
        lo = np.array([s.start for s in box]) - 1
        field = np.pad(np.where((labels[box] == k) | ~mask[box], data[box], 0.0), 1)
        peak_ijk_full = _peak(np.where(own, data[where], -np.inf)) + np.array([s.start for s in where])
        mesh = _surface(field, lo, affine, threshold)
        values = sign * np.maximum(_inner_values(data, affine, mesh), threshold)
        peak_mni = tuple(float(x) for x in (affine @ np.r_[peak_ijk_full, 1.0])[:3])
        centre = tuple(float(x) for x in mesh.center_mass)
        out.append(((np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64), values),
                    Cluster(sign, sign * float(data[tuple(peak_ijk_full)]), peak_mni, centre,  # type: ignore[arg-type]
                            float(mesh.volume), size)))
    return out


def _peak(values: NDArray[np.float64]) -> NDArray[np.int64]:
    """The voxel of the largest value, shape (3,); of several equal ones the nearest to their middle."""
    ties = np.argwhere(values == values.max())
    peak: NDArray[np.int64] = np.asarray(ties[np.argmin(np.linalg.norm(ties - ties.mean(axis=0), axis=1))],
                                         np.int64)
    return peak


def _surface(field: NDArray[np.float64], lo: NDArray[Any], affine: NDArray[np.float64],
             threshold: float) -> Any:
    """The isosurface of `field` (a padded crop starting at voxel `lo`) at `threshold`, in millimetres,
    smoothed, outward-facing (a trimesh.Trimesh)."""
    import trimesh
    from skimage.measure import marching_cubes

    verts, faces, _, _ = marching_cubes(field, level=threshold)  # type: ignore[no-untyped-call]
    ijk = verts + lo
    mm = ijk @ affine[:3, :3].T + affine[:3, 3]
    mesh = trimesh.Trimesh(mm, faces, process=True).subdivide_loop(iterations=1)  # rounder, 4x triangles
    passes, lamb, nu = TAUBIN
    trimesh.smoothing.filter_taubin(mesh, lamb=lamb, nu=nu, iterations=passes)  # type: ignore[no-untyped-call]
    if mesh.volume < 0:  # a mirrored affine (LAS) turns the triangles inside out
        mesh.invert()
    return mesh


def _inner_values(data: NDArray[np.float64], affine: NDArray[np.float64], mesh: Any) -> NDArray[np.float64]:
    """The largest value (of this sign) along each vertex's inward normal within :data:`DEPTH_MM`."""
    from scipy.ndimage import map_coordinates

    inverse = np.linalg.inv(affine)
    normals = np.asarray(mesh.vertex_normals, np.float64)
    vertices = np.asarray(mesh.vertices, np.float64)
    best = np.full(len(vertices), -np.inf)
    for depth in DEPTH_MM:
        points = vertices - depth * normals
        ijk = points @ inverse[:3, :3].T + inverse[:3, 3]
        best = np.maximum(best, map_coordinates(data, ijk.T, order=1, mode="nearest"))
    return best
