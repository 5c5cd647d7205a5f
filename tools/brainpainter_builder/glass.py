"""Glass brain: a smooth, light hull of each hemisphere's pial surface.

The pial surface is rasterised into a 1.5 mm grid (points on its triangles
less than half a voxel apart, so the voxel shell has no holes), filled,
closed morphologically with a ball (sulci disappear, the outer shape
stays), blurred, meshed by marching cubes, Taubin-smoothed and decimated to a
few thousand faces. The hull sits a millimetre or two outside the pial surface,
so it can be drawn as a transparent shell around the cortex.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals


def pial_hull(vertices: NDArray[Any], faces: NDArray[Any], *, voxel: float = 1.5,
              closing_radius: float = 8.0, blur: float = 2.5, target_faces: int = 6000,
              smooth_iterations: int = 20, offset: float = 1.0) -> tuple[NDArray[Any], NDArray[Any]]:
    """Smooth closed hull of a closed surface.

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
        Millimetres.
    faces : ndarray of int, shape (m, 3)
    voxel : float
        Grid spacing, mm.
    closing_radius : float
        Radius of the closing ball, mm (sulci narrower than twice it close).
    blur : float
        Gaussian smoothing of the closed volume before meshing, mm (sigma).
    target_faces : int
        Faces of the result.
    smooth_iterations : int
        Taubin passes before decimation.
    offset : float
        Final push along the vertex normals, mm, so that the few pial crowns
        that blurring shaved off stay inside the hull.

    Returns
    -------
    vertices : ndarray of float64, shape (k, 3)
    faces : ndarray of int64, shape (l, 3)
        Outward-facing.
    """
    from brainpainter.atlas.meshing import import_pymeshlab

    pymeshlab = import_pymeshlab()
    import trimesh
    from scipy import ndimage
    from skimage.measure import marching_cubes

    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    pad = int(np.ceil(closing_radius / voxel)) + 3
    origin = vertices.min(axis=0) - pad * voxel
    shape = tuple(np.ceil((vertices.max(axis=0) - origin) / voxel).astype(int) + pad + 1)
    points = surface_points(vertices, faces, 0.5 * voxel)
    ijk = np.floor((points - origin) / voxel).astype(np.int64)
    shell = np.zeros(shape, dtype=bool)
    shell[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = True
    solid = ndimage.binary_fill_holes(shell)
    # Closing by a ball, with exact Euclidean distances.
    r = closing_radius / voxel
    grown = ndimage.distance_transform_edt(~solid) <= r
    closed = ndimage.distance_transform_edt(grown) > r
    closed = ndimage.binary_fill_holes(closed | solid)
    field = ndimage.gaussian_filter(closed.astype(np.float32), sigma=blur / voxel)
    verts, tri, _, _ = marching_cubes(  # type: ignore[no-untyped-call]
        field, level=0.5, method="lewiner", allow_degenerate=False)
    tm = trimesh.Trimesh(verts, tri, process=True)
    trimesh.smoothing.filter_taubin(  # type: ignore[no-untyped-call]
        tm, lamb=0.5, nu=0.53, iterations=smooth_iterations)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(tm.vertices, dtype=np.float64),
                               face_matrix=np.asarray(tm.faces, dtype=np.int32)))
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=int(target_faces), optimalplacement=True, preservenormal=True,
        preservetopology=True, planarquadric=True, qualitythr=0.5, autoclean=True)
    mesh = ms.current_mesh()
    if not mesh.is_compact():
        mesh.compact()
    out_v = np.asarray(mesh.vertex_matrix(), dtype=np.float64) * voxel + origin + 0.5 * voxel
    out_f = np.asarray(mesh.face_matrix(), dtype=np.int64)
    a, b, c = (out_v[out_f[:, k]] for k in range(3))
    if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() < 0:
        out_f = out_f[:, ::-1]
    normals = vertex_normals(out_v, out_f, np.float64)
    out_v = out_v + offset * normals
    return out_v, np.ascontiguousarray(out_f)


def surface_points(vertices: NDArray[Any], faces: NDArray[Any], spacing: float) -> NDArray[Any]:
    """Points covering every triangle, no two neighbours further apart than `spacing`.

    Each face gets a regular barycentric grid with ``n`` steps per edge,
    ``n = ceil(longest edge / spacing)``.

    Returns
    -------
    points : ndarray of float64, shape (k, 3)
    """
    tri = vertices[faces]
    longest = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2).max(axis=1)
    steps = np.maximum(np.ceil(longest / spacing).astype(np.int64), 1)
    out = [vertices]
    for n in np.unique(steps):
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        w = np.stack([i[keep], j[keep], n - i[keep] - j[keep]], axis=1) / n  # (p, 3)
        out.append(np.einsum("pk,fkd->fpd", w, tri[steps == n]).reshape(-1, 3))
    return np.concatenate(out)
