"""Issue 44, items 10-13: mistakes that used to pass in silence are a one-line warning or error, with the
numbers (a threshold that keeps no edge, a matrix without names on an atlas whose size others share,
streamlines outside the brain, fsLR arrays given to the other hemisphere)."""

from __future__ import annotations

import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError

TINY_DK = ["Left-insula", "Left-precuneus", "Left-superiorfrontal", "Right-insula", "Right-precuneus",
           "Right-superiorfrontal"]
SMALL = {"views": "dorsal", "width": 160, "height": 120, "progress": False, "shading": "flat",
         "quality": "fast", "glass_opacity": 0.0}


def six_nodes(tmp_path) -> str:
    """The tiny template's six DK regions, every pair an edge, |weight| up to 0.9."""
    w = np.zeros((6, 6))
    iu = np.triu_indices(6, 1)
    w[iu] = np.linspace(0.1, 0.9, 15)
    path = tmp_path / "m.csv"
    rows = [",".join(["", *TINY_DK])] + [",".join([n, *map(repr, map(float, row))])
                                         for n, row in zip(TINY_DK, w + w.T, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def command(tmp_path, capsys, *args: str) -> tuple[int, list[str]]:
    """``brainpainter render`` with the stand-in renderer: exit code and the non-empty output lines."""
    from brainpainter.cli.main import main
    from brainpainter.testing import stand_in

    with stand_in() as renderer, pytest.raises(SystemExit) as exit_:
        main(["render", "--renderer", renderer, "--size", "80x60", "-q", "--out", str(tmp_path / "out"),
              "--views", "dorsal", *args])
    out = capsys.readouterr()
    return exit_.value.code or 0, [line for line in (out.out + out.err).splitlines() if line.strip()]


# -- item 11: a threshold that keeps no edge --------------------------------------------------------------
def test_a_threshold_above_every_weight_is_one_line_with_the_largest_weight(tmp_path, tiny, capsys):
    code, lines = command(tmp_path, capsys, "--connectome", six_nodes(tmp_path), "--atlas", "dk",
                          "--template", str(tiny), "--edge-threshold", "99")
    assert code == 2 and len(lines) == 1, lines
    assert "--edge-threshold 99 keeps no edge of connectome matrix" in lines[0]
    assert "largest |weight| is 0.9" in lines[0] and "'99%'" in lines[0]
    assert not (tmp_path / "out").exists()
    code, lines = command(tmp_path, capsys, "--connectome", six_nodes(tmp_path), "--atlas", "dk",
                          "--template", str(tiny), "--edge-threshold", "0.85")
    assert code == 0 and not any("keeps no edge" in line for line in lines), lines


def test_a_series_warns_for_the_matrices_a_threshold_empties_and_refuses_when_it_empties_all(tiny, tmp_path):
    (tmp_path / "nodes.csv").write_text("name,x,y,z\nleft,-35,0,20\nright,35,0,20\n")
    np.save(tmp_path / "fc.npy", np.stack([[[0.0, w], [w, 0.0]] for w in (0.2, 0.9, 0.3)]))
    kw = {"connectome": str(tmp_path / "fc.npy"), "nodes": str(tmp_path / "nodes.csv"), "template": str(tiny),
          **SMALL}
    with pytest.warns(UserWarning, match=r"--edge-threshold 0.5 keeps no edge of 2 of the 3 matrices of "
                                         r"connectome series .* their largest \|weight\| is 0.3 \(stage-1, "
                                         r"stage-3\): those images show the nodes only"):
        result = brainpainter.render(None, edge_threshold=0.5, **kw)
    assert [i["n_edges"] for i in result.manifest["connectome"]["series"]["images"]] == [0, 1, 0]
    with pytest.raises(BrainPainterError, match=r"keeps no edge of 3 of the 3 matrices .* largest \|weight\| "
                                                r"is 0.9;"):
        brainpainter.render(None, edge_threshold=1, **kw)
