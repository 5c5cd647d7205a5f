"""Pixels of a rendered image compared with a colour (the conformance checks' one test of a colour)."""

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
