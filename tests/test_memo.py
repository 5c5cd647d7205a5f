"""Work a figure of a map repeats kept in the process (issue 45's figure cost): the memo, template files,
meshes' edge tables and normals, a volume's voxel coordinates."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.io.memo import Memo, array_key


def test_memo_keeps_values_read_only_and_forgets_the_oldest_beyond_its_bytes():
    memo = Memo(max_bytes=2000)
    calls = []

    def make(n):
        calls.append(n)
        return np.zeros(n, np.uint8)

    a = memo.get("a", lambda: make(800))
    assert memo.get("a", lambda: make(1)) is a and calls == [800]  # kept, not computed again
    with pytest.raises(ValueError):
        a[0] = 1  # read-only: a caller cannot change the next caller's value
    memo.get("b", lambda: make(800))
    memo.get("c", lambda: make(800))  # 2400 bytes: the oldest ("a") goes
    assert len(memo) == 2 and memo.nbytes == 1600
    memo.get("a", lambda: make(800))
    assert calls == [800, 800, 800, 800]
    big = memo.get("big", lambda: make(5000))  # larger than the whole memo: still kept (the newest)
    assert memo.get("big", lambda: make(1)) is big and len(memo) == 1


def test_array_key_tells_content_dtype_and_shape_apart():
    a = np.arange(6, dtype=np.int32)
    assert array_key(a) == array_key(a.copy())
    assert array_key(a) != array_key(a.astype(np.int64))
    assert array_key(a) != array_key(a.reshape(2, 3))
    b = a.copy()
    b[5] = 7
    assert array_key(a) != array_key(b)
    assert array_key(a, b) != array_key(b, a)


def test_template_file_read_once_and_again_when_rewritten(tmp_path):
    from brainpainter.atlas.template import read_npz

    path = tmp_path / "part.npz"
    np.savez(path, faces=np.arange(6).reshape(2, 3))
    first = read_npz(path)
    assert read_npz(path) is first  # a second figure reads no file
    assert not first["faces"].flags.writeable
    np.savez(tmp_path / "new.npz", faces=np.arange(6).reshape(2, 3) + 1)
    (tmp_path / "new.npz").replace(path)  # rewritten: read again
    assert read_npz(path)["faces"][0, 0] == 1


def _sphere_mesh():
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2)
    return np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32)


def test_edge_table_of_the_same_mesh_built_once(monkeypatch):
    from brainpainter.rendering import mesh_edges, mesh_memo

    vertices, triangles = _sphere_mesh()
    palette = np.arange(len(vertices), dtype=np.int32) + 3
    built = []

    def counted(*args):
        built.append(1)
        return mesh_edges.edge_table(*args)

    monkeypatch.setattr(mesh_memo, "edge_table", counted)
    mesh_memo.MESH_MEMO.clear()
    first = mesh_memo.kept_edge_table(vertices, triangles, palette)
    again = mesh_memo.kept_edge_table(vertices.copy(), triangles.copy(), palette.copy())  # the next figure's
    assert again is first and built == [1]
    expected = mesh_edges.edge_table(vertices, triangles, palette)
    for name in ("ends", "faces", "border", "normals"):
        assert np.array_equal(getattr(first, name), getattr(expected, name))
    moved = vertices.copy()
    moved[0, 0] += 0.5  # another mesh: its own table
    mesh_memo.kept_edge_table(moved, triangles, palette)
    assert built == [1, 1]


def test_part_normals_the_same_when_kept():
    from brainpainter.atlas.mesh import vertex_normals
    from brainpainter.rendering.parts import build_part

    vertices, triangles = _sphere_mesh()
    slots = np.zeros(len(triangles), np.int64)
    sulc = np.zeros(len(vertices), np.float32)
    parts = [build_part("cortex-lh", "cortex", "lh", vertices, triangles, slots, sulc, first_slot=3)
             for _ in range(2)]
    assert parts[0] is not None and parts[1] is not None
    assert np.array_equal(parts[0].normals, vertex_normals(vertices, triangles))
    assert np.array_equal(parts[1].normals, parts[0].normals)


def _mni_volume(tmp_path, centre, name):
    import nibabel as nib

    affine = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in (91, 109, 91)], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    data = np.exp(-((xyz - centre) ** 2).sum(-1) / 200.0).astype(np.float32)
    path = tmp_path / f"{name}.nii.gz"
    nib.save(nib.Nifti1Image(data, affine), path)
    return path


def test_a_grid_sampled_at_coordinates_worked_out_once(tmp_path, monkeypatch):
    """Two volumes on one grid: the cortex's voxel coordinates are worked out for the first only, and
    each projection still follows its own voxels."""
    from brainpainter.maps import voxel_points
    from brainpainter.maps.volume import project_volume, subcortical_means

    worked = []
    original = voxel_points.voxel_coordinates

    def counted(affine, shape, points):
        worked.append(len(points))
        return original(affine, shape, points)

    monkeypatch.setattr(voxel_points, "voxel_coordinates", counted)
    voxel_points.VOXEL_MEMO.clear()
    right = project_volume(_mni_volume(tmp_path, [40, -20, 50], "right"))
    first = list(worked)
    left = project_volume(_mni_volume(tmp_path, [-40, -20, 50], "left"))
    assert first and worked == first  # the second volume: no coordinates worked out again
    assert np.nanmax(right["rh"]) > 0.5 > np.nanmax(right["lh"])
    assert np.nanmax(left["lh"]) > 0.5 > np.nanmax(left["rh"])
    voxel_points.VOXEL_MEMO.clear()
    assert np.array_equal(project_volume(_mni_volume(tmp_path, [-40, -20, 50], "left2"))["lh"], left["lh"],
                          equal_nan=True)  # kept or not, the same values
    means = subcortical_means(_mni_volume(tmp_path, [0, 0, 0], "middle"))
    again = subcortical_means(_mni_volume(tmp_path, [0, 0, 0], "middle2"))
    assert means == pytest.approx(again, nan_ok=True)
