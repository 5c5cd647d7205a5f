"""A series of connectivity matrices (issue 36): an image per matrix, a movie between them, bad series."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import brainpainter
from brainpainter.connectome.series import matrix_series
from brainpainter.errors import BrainPainterError

FLAT = {"shading": "flat", "quality": "fast", "glass_opacity": 0.0, "background": "white"}
SMALL = {"views": "dorsal", "width": 320, "height": 240, "progress": False, **FLAT}


def _near(img: np.ndarray, rgb, tol: float = 2) -> np.ndarray:
    return np.abs(img[..., :3].astype(float) - np.round(np.asarray(rgb, float)[:3] * 255)).max(axis=-1) <= tol


def pair(weight: float) -> np.ndarray:
    """Two nodes, one edge of `weight`."""
    return np.array([[0.0, weight], [weight, 0.0]])


@pytest.fixture
def nodes(tmp_path) -> str:
    """Two nodes of the tiny template, left and right."""
    path = tmp_path / "nodes.csv"
    path.write_text("name,x,y,z\nleft,-35,0,20\nright,35,0,20\n")
    return str(path)


def test_a_3_matrix_npy_renders_3_images_whose_edge_follows_each_matrix(tiny, tmp_path, nodes):
    weights = (0.2, 0.5, -0.8)
    np.save(tmp_path / "fc.npy", np.stack([pair(w) for w in weights]))
    result = brainpainter.render(None, connectome=str(tmp_path / "fc.npy"), nodes=nodes, template=str(tiny),
                                 out=tmp_path / "out", **SMALL)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert [f["file"] for f in manifest["files"]] == [f"stage-{t}_dorsal.png" for t in (1, 2, 3)]
    series = manifest["connectome"]["series"]
    assert series["n_matrices"] == 3 and [i["n_edges"] for i in series["images"]] == [1, 1, 1]
    assert [i["weight_range"] for i in series["images"]] == [[w, w] for w in weights]
    edges = result.layers[0].scale
    assert (edges.vmin, edges.vmax) == (-0.8, 0.8)  # one scale over the series, not each matrix's own
    from PIL import Image

    colours = [edges(np.array([w]))[0] for w in weights]
    for t in range(3):
        img = np.asarray(Image.open(tmp_path / "out" / f"stage-{t + 1}_dorsal.png"))
        assert _near(img, colours[t]).sum() > 10, t
        assert not any(_near(img, colours[s]).sum() for s in range(3) if s != t), t


def test_a_movie_of_two_matrices_draws_the_weight_between_them_halfway(tiny, tmp_path, nodes):
    from brainpainter.media.movie import MovieFrames, MovieKeys, MovieOptions, make_movie
    from brainpainter.media.timeline import plan_frames
    from brainpainter.rendering.run import prepare_run

    for name, w in (("a", 0.2), ("b", 0.8)):
        np.savetxt(tmp_path / f"{name}.csv", pair(w), delimiter=",")
    given = f"{tmp_path / 'a.csv'},{tmp_path / 'b.csv'}"
    options = {"connectome": given, "nodes": nodes, "template": str(tiny), **SMALL}
    del options["progress"]
    movie = make_movie(None, out=tmp_path / "m.gif", frames_per_step=4, progress=False, **options)
    assert (movie.n_frames, movie.keys) == (5, ["a", "b"])

    run = prepare_run(None, **options)
    keys = MovieKeys.of(None, run, [0, 1], MovieOptions(), True)
    plan = plan_frames(keys.times, 4, "linear", 0)
    frames = MovieFrames.of(run, keys, plan, MovieOptions(frames_per_step=4))
    middle = frames.frame_state[2]
    assert frames.states[middle][:3] == (0, 1, 0.5)
    (item,) = next(frames.chunks([middle]))
    with frames.painter as painter:
        img = painter.paint_colors(item.colors, item.view)
    scale = run.layers[0].scale
    assert _near(img, scale(np.array([0.5]))[0]).sum() > 10
    assert not _near(img, scale(np.array([0.2]))[0]).sum() and not _near(img, scale(np.array([0.8]))[0]).sum()


def test_matrices_of_different_shapes_exit_2_in_one_line_writing_nothing(tiny, tmp_path, nodes):
    from brainpainter.cli.main import main

    np.savetxt(tmp_path / "a.csv", pair(0.5), delimiter=",")
    np.savetxt(tmp_path / "b.csv", np.ones((3, 3)), delimiter=",")
    runner = CliRunner()
    with runner.isolation() as (out, err, _), pytest.raises(SystemExit) as exited:
        main(["render", "--connectome", f"{tmp_path / 'a.csv'},{tmp_path / 'b.csv'}", "--nodes", nodes,
              "--template", str(tiny), "--out", str(tmp_path / "out")])
    said = (out.getvalue() + (err.getvalue() if err else b"")).decode()
    assert exited.value.code == 2, said
    lines = [line for line in said.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in said
    assert "b.csv' is 3 x 3 but matrix" in lines[0] and "a.csv' is 2 x 2" in lines[0]
    assert not (tmp_path / "out").exists()


def test_a_stack_of_different_arrays_and_a_table_of_other_rows_are_refused(tiny, nodes):
    with pytest.raises(BrainPainterError, match=r"matrix array 2 is 3 x 3 but matrix array 1 is 2 x 2"):
        matrix_series([pair(0.1), np.ones((3, 3))])
    with pytest.raises(BrainPainterError, match=r"has 2 matrices but table .* has 1 image"):
        brainpainter.render({"Left-precentral": [1.0]}, atlas="dk", nodes=nodes, template=str(tiny),
                            connectome=np.stack([pair(0.1), pair(0.2)]), **SMALL)


def test_a_folder_or_a_glob_is_sorted_by_name_numbers_by_value(tmp_path):
    for name in ("t10", "t2", "t1"):
        np.savetxt(tmp_path / f"{name}.csv", pair(0.5), delimiter=",")
    (tmp_path / "notes.md").write_text("not a matrix")
    assert matrix_series(str(tmp_path)).names == ("t1", "t2", "t10")
    assert matrix_series(str(tmp_path / "t*.csv")).names == ("t1", "t2", "t10")
    assert matrix_series(str(tmp_path / "t1.csv")) is None  # one matrix
    with pytest.raises(BrainPainterError, match="matches no file"):
        matrix_series(str(tmp_path / "x*.csv"))


def test_a_3d_npy_is_read_one_matrix_at_a_time(tmp_path):
    np.save(tmp_path / "fc.npy", np.arange(3 * 4 * 4, dtype=np.float32).reshape(3, 4, 4))
    series = matrix_series(str(tmp_path / "fc.npy"))
    assert series is not None and series.names == ("stage-1", "stage-2", "stage-3") and series.array is None
    np.testing.assert_array_equal(series.matrix(2).weights, np.arange(32, 48).reshape(4, 4))
    np.save(tmp_path / "odd.npy", np.zeros((3, 4, 5)))
    with pytest.raises(BrainPainterError, match="holds 3 matrices of 4 x 5"):
        matrix_series(str(tmp_path / "odd.npy"))


def test_a_mat_of_n_by_n_by_t_is_a_series(tmp_path):
    import scipy.io

    stack = np.stack([pair(w) for w in (0.1, 0.2, 0.3)], axis=2)  # MATLAB's N x N x T
    scipy.io.savemat(tmp_path / "fc.mat", {"W": stack})
    series = matrix_series(str(tmp_path / "fc.mat"))
    assert series is not None and len(series) == 3
    assert series.matrix(1).weights[0, 1] == 0.2


def test_scene_add_takes_a_series(tiny, nodes):
    from brainpainter import Scene
    from brainpainter.testing import stand_in

    with stand_in() as renderer:
        scene = Scene(template=str(tiny), renderer=renderer, width=160, height=120)
        drawn = scene.add([pair(0.3), pair(-0.6)], kind="connectome", nodes=nodes).render(views="dorsal",
                                                                                          progress=False)
    assert sorted(drawn.images) == [("stage-1", "dorsal"), ("stage-2", "dorsal")]
    assert [i["weight_range"] for i in drawn.manifest["connectome"]["series"]["images"]] == [[0.3, 0.3],
                                                                                           [-0.6, -0.6]]


def test_a_series_with_a_table_takes_matrix_i_for_row_i(tiny, nodes):
    from brainpainter.rendering.run import prepare_run
    from brainpainter.rendering.views import get_view

    table = {"image": ["before", "after"], "Left-precentral": [1.0, 2.0]}
    run = prepare_run(table, "dk", connectome=np.stack([pair(0.3), pair(-0.6)]), nodes=nodes,
                      template=str(tiny))
    edges = run.scale_of("edges")
    for row, w in ((0, 0.3), (1, -0.6)):
        expected = tuple(float(c) for c in edges(np.array([w]))[0])
        assert run.item(row, get_view("dorsal")).colors["edge:0"] == expected


def test_the_export_of_a_series_row_shows_that_matrix_weight(tmp_path, tiny, nodes):
    import struct

    stack = np.stack([pair(0.3), pair(-0.6)])
    glb = brainpainter.export(None, tmp_path / "c.glb", row="stage-1", connectome=stack, nodes=nodes,
                              template=str(tiny)).read_bytes()
    doc = json.loads(glb[20:20 + struct.unpack("<I", glb[12:16])[0]])
    extras = {node["name"]: node["extras"] for node in doc["nodes"] if node["extras"]["part"] == "connectome"}
    assert extras["left \u2013 right"]["value"] == "0.3"  # not -0.6, its largest over the series


@pytest.mark.parametrize(("suffix", "shape", "message"), [
    (".npy", (6, 6, 3), r"is 6 x 6 x 3: 3 matrices of 6 x 6 with time last, but a series array or \.npy "
                        r"is T x N x N \(time first\); move the last axis first \(numpy\.moveaxis\(fc, -1, "
                        r"0\)\)"),
    (".mat", (3, 6, 6), r"is 3 x 6 x 6: 3 matrices of 6 x 6 with time first, but a \.mat series is N x N "
                        r"x T \(MATLAB keeps time last\); move the first axis last \(MATLAB: permute\(fc, "
                        r"\[2 3 1\]\)"),
])
def test_a_series_with_time_on_the_other_axis_says_which_axis_to_move(tmp_path, suffix, shape, message):
    """Issue 44 item 15: a T x N x N .mat or an N x N x T .npy said only 'holds 6 matrices of 6 x 3'."""
    import scipy.io

    path = tmp_path / f"fc{suffix}"
    if suffix == ".npy":
        np.save(path, np.ones(shape))
    else:
        scipy.io.savemat(path, {"fc": np.ones(shape)})
    with pytest.raises(BrainPainterError, match=message):
        matrix_series(str(path))
    with pytest.raises(BrainPainterError, match="holds 2 matrices of 6 x 5; a series is T x N x N"):
        matrix_series(np.ones((2, 6, 5)))
