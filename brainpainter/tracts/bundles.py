"""What core holds of loaded tracts: bundles of resampled, oriented streamlines (:class:`Tracts`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Tracts:
    """Bundles of streamlines in template coordinates.

    Attributes
    ----------
    names : tuple of str
        Canonical bundle names (:func:`brainpainter.tracts.names.canonical`), unique.
    lines : ndarray of float32, shape (n_streamlines, n_points, 3)
        Resampled, oriented consistently within each bundle, RAS millimetres of the template.
    bundle : ndarray of int32, shape (n_streamlines,)
        Index into `names` of each streamline.
    counts : tuple of int
        Streamlines of each bundle in its file(s) (before subsampling).
    notes : tuple of str
        What was drawn where it differs from what was given (subsampling).
    """

    names: tuple[str, ...]
    lines: NDArray[Any]
    bundle: NDArray[Any]
    counts: tuple[int, ...]
    notes: tuple[str, ...] = ()

    @property
    def n_points(self) -> int:
        return int(self.lines.shape[1])

    def drawn(self, i: int) -> int:
        """Streamlines of bundle `i` that are drawn."""
        return int(np.count_nonzero(self.bundle == i))

    def summary(self) -> dict[str, Any]:
        """JSON-ready: bundles, streamlines in the files and drawn, notes."""
        return {"bundles": [{"name": n, "streamlines": c, "drawn": self.drawn(i)}
                            for i, (n, c) in enumerate(zip(self.names, self.counts, strict=True))],
                "notes": list(self.notes)}
