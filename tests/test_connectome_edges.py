"""select_edges: a threshold on |weight| or a percentile, the K strongest, the edges of one node; combined."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.connectome.edges import parse_threshold, select_edges
from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError


def connectome(n: int = 6, directed: bool = False, seed: int = 0) -> Connectome:
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, (n, n))
    if not directed:
        w = np.triu(w, 1) + np.triu(w, 1).T
    np.fill_diagonal(w, np.nan)
    return Connectome(names=tuple(f"n{i}" for i in range(n)), positions=np.zeros((n, 3)), weights=w,
                      directed=directed)


def kept(conn: Connectome) -> set[tuple[int, int]]:
    s, t, _ = conn.edges()
    return set(zip(s.tolist(), t.tolist(), strict=True))


def test_threshold_number_keeps_abs_weight_at_least_it_and_stays_symmetric():
    conn = connectome()
    out = select_edges(conn, threshold=0.5)
    s, t, w = conn.edges()
    assert kept(out) == {(a, b) for a, b, x in zip(s, t, w, strict=True) if abs(x) >= 0.5}
    assert np.array_equal(np.isnan(out.weights), np.isnan(out.weights.T))
    assert out.names == conn.names and out.positions is conn.positions
    assert select_edges(conn, threshold="0.5").weights.tobytes() == out.weights.tobytes()


def test_percentile_keeps_that_share_of_the_upper_triangle_counted():
    conn = connectome(40)  # 780 edges
    assert len(select_edges(conn, threshold="95%").edges()[0]) == 39
    assert len(select_edges(conn, threshold="99 %").edges()[0]) == 8
    strongest = select_edges(conn, threshold="95%")
    rest = np.where(np.isnan(strongest.weights), np.abs(conn.weights), np.nan)
    assert np.nanmin(np.abs(strongest.weights)) >= np.nanmax(rest)
    directed = connectome(40, directed=True)  # 1560 off-diagonal edges
    assert len(select_edges(directed, threshold="95%").edges()[0]) == 78


def test_top_k_and_edges_of_and_all_combined():
    conn = connectome(10)
    top = select_edges(conn, top=3)
    w = np.abs(conn.edges()[2])
    assert len(top.edges()[0]) == 3 and set(np.abs(top.edges()[2])) == set(np.sort(w)[-3:])
    of = select_edges(conn, edges_of="N4")  # case-insensitive
    assert kept(of) == {(min(4, j), max(4, j)) for j in range(10) if j != 4}
    both = select_edges(conn, edges_of="n4", threshold=0.2, top=2)
    strong = [(abs(conn.weights[4, j]), j) for j in range(10) if j != 4 and abs(conn.weights[4, j]) >= 0.2]
    expect = sorted(strong, reverse=True)[:2]
    assert kept(both) == {(min(4, j), max(4, j)) for _, j in expect}
    assert select_edges(conn, top=0).edges()[0].size == 0


@pytest.mark.parametrize("bad", ["-1", "abc", "120%", "nan", True, "-5%"])
def test_bad_thresholds_are_one_line(bad):
    with pytest.raises(BrainPainterError, match="the edge threshold must be a number >= 0") as exc:
        parse_threshold(bad)
    assert "\n" not in str(exc.value) and "was given" in str(exc.value)


def test_bad_top_and_unknown_edges_of_node():
    conn = connectome()
    with pytest.raises(BrainPainterError, match="whole number >= 0"):
        select_edges(conn, top=-1)
    with pytest.raises(BrainPainterError) as exc:
        select_edges(conn, edges_of="n44")
    assert "'n44' is not a node of the connectome" in str(exc.value) and "did you mean 'n4'" in str(exc.value)


# -- issue 46: at most MAX_EDGES_DRAWN edges, labels of a bounded length ---------------------------
def test_a_dense_matrix_draws_its_strongest_5000_edges_with_a_note():
    """1000 nodes, every edge (499,500): the strongest 5000 are drawn, whatever the options."""
    from brainpainter.connectome.edges import MAX_EDGES_DRAWN
    from brainpainter.connectome.options import ConnectomeOptions
    from brainpainter.rendering.connectome_layers import connectome_summary

    conn = connectome(1000)
    _, _, w = conn.edges()
    assert len(w) == 499_500 and MAX_EDGES_DRAWN == 5000
    out = ConnectomeOptions(connectome="given").chosen(conn)  # no option given: the cap still applies
    _, _, drawn = out.edges()
    assert len(drawn) == 5000 and out.edges_left_out == 494_500
    assert np.abs(drawn).min() >= np.sort(np.abs(w))[-5000]  # the strongest
    summary = connectome_summary(out)
    assert summary["n_edges"] == 5000 and summary["edges_left_out"] == 494_500
    assert "the strongest 5000 of 499500 edges are drawn" in summary["note"]
    top = select_edges(conn, top=1_000_000)
    assert top.edges_left_out == 494_500
    few = select_edges(conn, top=10)
    assert few.edges_left_out == 0 and len(few.edges()[2]) == 10


def test_node_labels_are_drawn_at_most_60_characters_without_control_characters():
    import dataclasses

    from brainpainter.connectome.model import MAX_LABEL_CHARS

    conn = dataclasses.replace(connectome(3), node_labels=("a" * 100_000, "b\x1b[31mc\r", ""))
    texts = conn.label_texts()
    assert MAX_LABEL_CHARS == 60 and len(texts[0]) == 60 and texts[0].endswith("\u2026")
    assert texts[1] == "b [31mc " and texts[2] == ""
