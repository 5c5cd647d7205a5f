"""Stand-in renderers for tests/test_parallel.py, importable by worker processes (tests/ is on sys.path).

Module-level subclasses of the one stand-in (worker processes import them by name).
"""

from __future__ import annotations

from brainpainter.testing import StandInRenderer


def _first_image_fails(n: int) -> BaseException | None:
    return RuntimeError("transient failure (first image of this worker)") if n == 1 else None


class SlowStandIn(StandInRenderer):
    """A stand-in that takes 0.15 s an image, so a run lasts long enough to kill a worker in it."""

    delay = 0.15


class FlakyStandIn(StandInRenderer):
    """A stand-in whose first image in each process fails (as a worker that hits a transient error)."""

    fail = staticmethod(_first_image_fails)
