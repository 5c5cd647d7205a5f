"""The edges that the default draw path anti-aliases (brainpainter_blender.edge_aa), without Blender."""

from __future__ import annotations

import numpy as np
import trimesh

from brainpainter.rendering.parts import split_by_label
from brainpainter_blender.edge_aa import edge_table, visible_edges

#: Towards a camera that sees the +x, +y and +z faces of a cube.
BACK = np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0])


def _cube(top_slot: int = 0):
    box = trimesh.creation.box()
    top = box.face_normals[:, 2] > 0.5
    face_slot = np.where(top, top_slot, 0)
    vertices, faces, slots, _ = split_by_label(box.vertices, box.faces, face_slot)
    return vertices, faces, slots


def test_a_closed_mesh_has_silhouettes_only():
    vertices, faces, slots = _cube()
    table = edge_table(vertices, faces, slots)
    assert len(table.ends) == 18  # 12 edges of the cube, 6 diagonals of its faces
    assert (table.faces >= 0).all() and not table.border.any()
    ends = vertices[table.ends[visible_edges(table, BACK)]]
    assert len(ends) == 6  # the hexagon around the three faces seen
    # each silhouette edge lies between a face seen and one not seen: on none of the seen faces' centres
    for axis in range(3):
        assert not np.all(np.isclose(ends[:, :, axis], 0.5), axis=1).all()


def test_region_borders_join_the_copies_of_their_vertices():
    vertices, faces, slots = _cube(top_slot=1)
    assert len(vertices) > 8  # the top face's corners are copies
    table = edge_table(vertices, faces, slots)
    assert len(table.ends) == 18 and (table.faces >= 0).all()
    assert table.border.sum() == 4  # the top face's four edges
    assert len(visible_edges(table, BACK)) == 8  # the hexagon and the top's two edges inside it
    assert len(visible_edges(table, -BACK)) == 6  # from behind: the hexagon; the top faces away


def test_open_boundaries_count_when_their_triangle_faces_the_camera():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    table = edge_table(vertices, np.array([[0, 1, 2]]), np.zeros(3, np.int32))
    assert len(table.ends) == 3 and (table.faces[:, 1] == -1).all()
    assert len(visible_edges(table, np.array([0.0, 0.0, 1.0]))) == 3
    assert len(visible_edges(table, np.array([0.0, 0.0, -1.0]))) == 0


def test_a_map_cortex_has_no_region_borders():
    vertices, faces, _ = _cube()
    per_vertex = np.arange(len(vertices))  # a map: slots differ within triangles
    assert not edge_table(vertices, faces, per_vertex).border.any()


def test_front_faces_are_those_facing_an_orthographic_camera():
    # the default draw path leaves out, per view, the triangles back-face culling would drop
    from brainpainter_blender.facing import front_faces

    sphere = trimesh.creation.icosphere(subdivisions=3)
    mvp = np.diag([0.5, 0.5, -0.01, 1.0])  # orthographic, looking down -z (towards the viewer: +z)
    kept = front_faces(sphere.vertices, sphere.faces, mvp)
    normals = trimesh.triangles.normals(sphere.vertices[kept])[0]
    assert (normals[:, 2] >= -1e-9).all()
    assert len(kept) == int((sphere.face_normals[:, 2] >= -1e-9).sum())
    assert 0.4 * len(sphere.faces) < len(kept) < 0.6 * len(sphere.faces)
    # an image mirrored (x flipped) turns the winding on screen, for culling as for this
    mirrored = front_faces(sphere.vertices, sphere.faces, np.diag([-0.5, 0.5, -0.01, 1.0]))
    assert (trimesh.triangles.normals(sphere.vertices[mirrored])[0][:, 2] <= 1e-9).all()


def test_back_faces_are_the_rest_for_the_glass_far_side():
    # the glass's far side draws, per view, only the triangles front-face culling keeps
    from brainpainter_blender.facing import front_faces

    sphere = trimesh.creation.icosphere(subdivisions=3)
    mvp = np.diag([0.5, 0.5, -0.01, 1.0])
    front = front_faces(sphere.vertices, sphere.faces, mvp)
    back = front_faces(sphere.vertices, sphere.faces, mvp, back=True)
    assert (trimesh.triangles.normals(sphere.vertices[back])[0][:, 2] <= 1e-9).all()
    # every triangle on one side (edge-on ones, of no area on screen, on both)
    both = {tuple(t) for t in front} & {tuple(t) for t in back}
    assert len(front) + len(back) - len(both) == len(sphere.faces)
    assert len(both) < 0.1 * len(sphere.faces)


def test_facing_from_kept_normals_is_the_sign_of_the_area_on_screen():
    # a new view (a movie's orbit) tests each triangle against kept normals: the same triangles
    # as the signed area of its corners projected by any orthographic camera, mirrored or turned
    from brainpainter_blender.facing import facing, triangle_normals

    rng = np.random.default_rng(0)
    vertices = rng.normal(size=(200, 3)) * 50
    triangles = rng.integers(0, 200, size=(500, 3))
    normals = triangle_normals(vertices, triangles)
    assert normals.shape == (3, 500)
    for _ in range(5):
        q, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        mvp = np.eye(4)
        mvp[:3, :3] = q * rng.choice([-1, 1], 3) * [0.01, 0.02, -0.001]
        mvp[:3, 3] = rng.normal(size=3)
        xy = vertices @ mvp[:2, :3].T
        a, b, c = xy[triangles[:, 0]], xy[triangles[:, 1]], xy[triangles[:, 2]]
        area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        assert (facing(normals, mvp) == (area >= 0)).all()
        assert (facing(normals, mvp, back=True) == (area <= 0)).all()
