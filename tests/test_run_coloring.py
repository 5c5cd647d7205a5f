"""A run says how it is coloured (``Run.coloring``: its first layer's; issue 43: no ``hasattr`` on
runs), and a painter of the other colouring is refused before anything is drawn."""

from __future__ import annotations

import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.run import prepare_run
from brainpainter.testing import stand_in


def test_a_table_run_colours_regions_and_a_map_run_vertices():
    assert prepare_run({"Left-insula": 1.0}, "dk").coloring == "regions"
    assert prepare_run({"lh": np.zeros(10242), "rh": np.ones(10242)}, "dk").coloring == "vertices"


@pytest.mark.parametrize(("coloring", "data", "said"), [
    ("regions", {"lh": np.zeros(10242), "rh": np.ones(10242)}, "colours regions but the data is a map"),
    ("vertices", {"Left-insula": 1.0}, "colours vertices but the data is a region table"),
])
def test_a_painter_of_the_other_colouring_is_refused(coloring, data, said):
    with stand_in() as renderer:
        painter = Painter("dk", renderer=renderer, coloring=coloring)
        with pytest.raises(BrainPainterError, match=said):
            brainpainter.render(data, painter=painter, progress=False)
