"""Memory growth per image: memory sampled after each render, with a robust slope.

A renderer (or a pipeline) that keeps something per image grows by that much
per image; one-off growth (a cache filled once, the allocator taking a new
arena) does not. :func:`growth_per_image` renders after a warm-up, samples
two measures after every image and returns the larger Theil-Sen slope (the
median of the slopes between all pairs of samples), which ignores spikes and
a single step but follows a steady leak even when memory comes in chunks of
several images:

* the resident set size, which sees every allocation (Blender's C heap too)
  but not one that reuses memory freed earlier in the process;
* the bytes allocated through Python and numpy since the measurement began
  (:mod:`tracemalloc`), which sees such a leak however much memory is free.
"""

from __future__ import annotations

import gc
import os
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

STATM = Path("/proc/self/statm")


def can_measure() -> bool:
    """Whether resident memory can be read (Linux ``/proc``)."""
    return STATM.exists()


def rss_mb() -> float:
    """Resident set size of this process, in MB (2**20 bytes)."""
    with STATM.open() as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def theil_sen(samples: ArrayLike) -> float:
    """Median slope between all pairs of `samples`, shape (n,), taken at steps 0, 1, ..., n - 1."""
    y = np.asarray(samples, dtype=float)
    i, j = np.triu_indices(len(y), k=1)
    return float(np.median((y[j] - y[i]) / (j - i)))


def growth_per_image(render_one: Callable[[int], object], n: int = 120, warmup: int = 20) -> float:
    """Memory growth per image in MB: the larger Theil-Sen slope of resident and traced memory.

    Parameters
    ----------
    render_one : callable
        ``render_one(i)`` draws image number i (its result is dropped).
    n, warmup : int
        Images measured, and drawn before measuring.

    Returns
    -------
    float
        MB per image (about 0 for a renderer that keeps nothing per image).
    """
    for i in range(warmup):
        render_one(i)
    gc.collect()
    started = not tracemalloc.is_tracing()
    if started:
        tracemalloc.start()
    rss, traced = [], []
    try:
        for i in range(n):
            render_one(warmup + i)
            rss.append(rss_mb())
            traced.append(tracemalloc.get_traced_memory()[0] / 2**20)
    finally:
        if started:
            tracemalloc.stop()
    return max(theil_sen(rss), theil_sen(traced))
