"""Pixels of a rendered image compared with a colour (the conformance checks' one test of a colour), and the
tiny template's region colours the checks paint."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

#: The background of the conformance checks' images (sRGB 0-1).
WHITE = (1.0, 1.0, 1.0)


def near(img: NDArray[np.uint8], rgb: Any, tol: float) -> NDArray[np.bool_]:
    """Pixels of `img`, shape (h, w, 4), within `tol` (0-255 units) of colour `rgb`; shape (h, w)."""
    target = np.round(np.asarray(rgb, dtype=float)[:3] * 255)
    return np.asarray(np.abs(img[..., :3].astype(float) - target).max(axis=-1) <= tol)


RGB = tuple[float, float, float]
#: Distinct flat colours of the tiny template's regions (sRGB 0-1).
COLORS: dict[str, RGB] = {
    "Left-insula": (0.90, 0.10, 0.10), "Left-precuneus": (0.10, 0.75, 0.20),
    "Left-superiorfrontal": (0.15, 0.25, 0.95), "Left-unknown": (0.95, 0.85, 0.10),
    "Right-insula": (0.85, 0.15, 0.85), "Right-precuneus": (0.10, 0.80, 0.85),
    "Right-superiorfrontal": (1.00, 0.55, 0.05), "Right-unknown": (0.45, 0.20, 0.70),
    "Left-Hippocampus": (0.60, 0.05, 0.05), "Right-Hippocampus": (0.05, 0.35, 0.60),
}
