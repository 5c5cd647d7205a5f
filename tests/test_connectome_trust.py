"""Issue 44, items 1-9: a connectome's layers true to their own bars beside other layers, and dense graphs
that read (one hemisphere per lateral view, Yeo's network colours, labels that can be read)."""

from __future__ import annotations

import numpy as np

from brainpainter.rendering.run import prepare_run
from brainpainter.testing.connectome_check import tiny_connectome


def test_a_label_never_moves_the_plain_scale_onto_the_edges(tiny):
    """Item 3: ``--cmap viridis --edges-label FC`` keeps viridis on the regions; the edges keep RdBu_r about 0."""
    table = {"Left-insula": 1.0, "Right-insula": 2.0}
    plain = prepare_run(table, "dk", template=str(tiny), connectome=tiny_connectome(), cmap="viridis")
    labelled = prepare_run(table, "dk", template=str(tiny), connectome=tiny_connectome(), cmap="viridis",
                           edges_label="FC", nodes_label="strength")
    for run in (plain, labelled):
        layers = {layer.kind: layer.scale for layer in run.layers}
        assert layers["regions"].name == "viridis"
        assert (layers["edges"].name, layers["edges"].center) == ("RdBu_r", 0.0)
        assert layers["edges"].vmin == -layers["edges"].vmax
        assert layers["nodes"].to_dict() == {k.kind: k.scale for k in plain.layers}["nodes"].to_dict()
    assert [layer.label for layer in labelled.layers][1:] == ["FC", "strength"]
