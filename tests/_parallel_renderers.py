"""Stand-in renderers for tests/test_parallel.py, importable by worker processes (tests/ is on sys.path)."""

from __future__ import annotations

import time

from brainpainter.testing import StandInRenderer


class SlowStandIn(StandInRenderer):
    """A stand-in that takes 0.15 s an image, so a run lasts long enough to kill a worker in it."""

    def render(self, colors, view):
        time.sleep(0.15)
        return super().render(colors, view)


class FlakyStandIn(StandInRenderer):
    """A stand-in whose first image in each process fails (as a worker that hits a transient error)."""

    failed = False

    def render(self, colors, view):
        if not type(self).failed:
            type(self).failed = True
            raise RuntimeError("transient failure (first image of this worker)")
        return super().render(colors, view)
