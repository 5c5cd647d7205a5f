"""Two synthetic white-matter bundles inside the tiny template (the conformance suite's tracts check)."""

from __future__ import annotations

from typing import Any

import numpy as np


def tiny_tracts() -> Any:
    """Two synthetic bundles for the tiny template: ``AF_left`` along y at x = -35, ``CST_right`` along z.

    Returns
    -------
    brainpainter.tracts.model.Tracts
        20 streamlines of 16 points each per bundle.
    """
    from brainpainter.tracts.model import Tracts

    rng = np.random.default_rng(0)
    t = np.linspace(-1.0, 1.0, 16)
    lines = []
    for i in range(40):
        jitter = rng.normal(0.0, 1.5, 3)
        if i < 20:
            pts = np.column_stack([np.full(16, -35.0), 30 * t, 20 + 5 * np.cos(t * 1.5)]) + jitter
        else:
            pts = np.column_stack([np.full(16, 35.0) + 3 * np.sin(t * 2), np.zeros(16), 30 * t]) + jitter
        lines.append(pts)
    bundle = np.repeat(np.arange(2, dtype=np.int32), 20)
    return Tracts(("AF_left", "CST_right"), np.asarray(lines, np.float32), bundle, (20, 20))
