"""Render on several processes (``--jobs``) or a Dask cluster (``--scheduler``), with the serial result.

A run's images are independent, so they are split into chunks (a few
images each) and painted by workers that each hold a warm
:class:`~brainpainter.rendering.painter.Painter`: the scene is loaded once per worker,
and a task carries only the colours of its images, their views and their PNG
text (never meshes). Workers return PNG bytes (or pixel arrays, on one
machine); the calling process writes every file, through the same code as a
serial run, so the output is byte-identical to it.

* :class:`LocalRunner`: a pool of N processes on this machine (``spawn``, so
  no process inherits a loaded Blender). Each worker sets Mesa llvmpipe's
  thread count (``LP_NUM_THREADS``) to its share of the cores before Blender
  starts, so N workers do not oversubscribe the machine.
* :class:`brainpainter.rendering.cluster.DaskRunner`: a ``dask.distributed`` cluster (a LocalCluster, SLURM
  through dask-jobqueue, Kubernetes...). A :class:`~brainpainter.rendering.cluster.PainterPlugin` (a
  worker plugin) holds the warm painter of each worker, also of workers that
  join or are restarted later; tasks that fail are retried (reported on
  stderr), and tasks of a worker that dies are rescheduled by Dask.
* :class:`SerialRunner`: the same interface on a painter in this process.

>>> render("cohort.csv", out="out/", jobs="auto")             # doctest: +SKIP
>>> render("cohort.csv", out="out/", client=dask_client)      # doctest: +SKIP
"""

from __future__ import annotations

import io
import math
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.options import cpu_count, resolve_jobs
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.painter_spec import PainterSpec

__all__ = ["Item", "LocalRunner", "PainterSpec", "Runner", "SerialRunner", "chunk_size", "chunked", "drive",
           "paint_all", "paint_items", "resolve_jobs"]

if TYPE_CHECKING:  # pragma: no cover
    from brainpainter.rendering.settings import RGB
    from brainpainter.rendering.views import View

SCHEDULER_ENV = "BRAINPAINTER_SCHEDULER"
#: Times a Dask task that raised (not a user error) is sent again before the run fails.
RETRIES = 2
#: How long to wait for the first Dask worker of a cluster that has none yet.
WORKER_WAIT_S = 300.0


# -- sizes ------------------------------------------------------------------------------
def render_threads(jobs: int) -> int:
    """Renderer threads per worker so that `jobs` workers share this machine's cores."""
    return max(1, cpu_count() // max(1, jobs))


def chunk_size(n_items: int, n_workers: int, largest: int = 8) -> int:
    """Images per task: about four tasks per worker (even load, a live progress bar), 1 to `largest`."""
    return max(1, min(largest, math.ceil(n_items / (4 * max(1, n_workers)))))


def chunked(items: Sequence[Any], size: int) -> list[list[Any]]:
    """`items` in consecutive lists of `size` (the last may be shorter)."""
    return [list(items[k:k + size]) for k in range(0, len(items), size)]


# -- what a worker needs -------------------------------------------------------------
@dataclass(frozen=True)
class Item:
    """One image to paint.

    Attributes
    ----------
    colors : dict of str to (float, float, float)
        sRGB 0-1 colour of each region key (:func:`brainpainter.rendering.painter.region_colors`).
    view : View
    metadata : dict of str to str, optional
        PNG text chunks, for images returned as PNG files.
    label : str
        What the image is (an image name, a frame), for messages about a failed task.
    """

    colors: Mapping[str, RGB]
    view: View
    metadata: Mapping[str, str] | None = None
    label: str = ""


def paint_items(painter: Painter, items: Iterable[Item], encode: bool) -> list[Any]:
    """Paint `items`: RGBA uint8 arrays of shape (h, w, 4), or PNG bytes when `encode`."""
    from brainpainter.io.output import png_bytes

    out: list[Any] = []
    for item in items:
        pixels = painter.paint_colors(item.colors, item.view)
        out.append(png_bytes(pixels, dict(item.metadata or {})) if encode else pixels)
    return out


def decode_png(data: bytes) -> NDArray[Any]:
    """PNG bytes -> RGBA uint8 array of shape (h, w, 4) (lossless: the array that was encoded)."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGBA"))


class WarmPainter:
    """A painter built from a spec on first use and kept for the process's (or plugin's) life."""

    def __init__(self, spec: PainterSpec) -> None:
        self.spec = spec
        self.painter: Painter | None = None
        self.load_seconds = 0.0
        self._lock = threading.Lock()

    def get(self) -> Painter:
        with self._lock:
            if self.painter is None:
                t0 = time.perf_counter()
                painter = self.spec.build()
                painter.load()
                self.painter = painter
                self.load_seconds = time.perf_counter() - t0
            return self.painter

    def close(self) -> None:
        with self._lock:
            if self.painter is not None:
                self.painter.close()
                self.painter = None


# -- the generic loop ------------------------------------------------------------------
def drive(chunks: Iterable[Sequence[Item]], submit: Callable[[Sequence[Item]], Any],
           wait_any: Callable[[list[Any]], Iterable[Any]], collect: Callable[[Any, Sequence[Item]], Any],
           window: int | Callable[[], int], ordered: bool) -> Iterator[tuple[int, list[Any]]]:
    """Keep at most `window` chunks submitted or waiting; yield ``(chunk index, results)``.

    `collect(future, chunk)` returns the chunk's results, or a new future
    (a retry) wrapped in ``Retry``. With `ordered`, results come in chunk order.
    `window` may be a callable, asked again after each batch of results (a
    cluster whose workers come and go).
    """
    source = enumerate(chunks)
    pending: dict[Any, tuple[int, Sequence[Item]]] = {}
    ready: dict[int, list[Any]] = {}
    next_index, exhausted = 0, False
    while True:
        limit = window() if callable(window) else window
        while not exhausted and len(pending) + len(ready) < limit:
            try:
                index, chunk = next(source)
            except StopIteration:
                exhausted = True
                break
            pending[submit(chunk)] = (index, chunk)
        if not pending:
            return
        for future in wait_any(list(pending)):
            index, chunk = pending.pop(future)
            result = collect(future, chunk)
            if isinstance(result, Retry):
                pending[result.future] = (index, chunk)
            elif ordered:
                ready[index] = result
            else:
                yield index, result
        while ordered and next_index in ready:
            yield next_index, ready.pop(next_index)
            next_index += 1


@dataclass(frozen=True)
class Retry:
    """A task sent again: its new future."""

    future: Any


@dataclass
class Runner:
    """Paints chunks of :class:`Item` somewhere; used as a context manager.

    Attributes
    ----------
    n_workers : int
    startup_seconds : list of float
        Time each worker took to start its painter (import the renderer, load the scene).
    retried : list of str
        One line per task that failed and was sent again.
    start_wall : float
        Seconds :meth:`start` took (starting processes or reaching the cluster, and warming every painter).
    """

    n_workers: int = 1
    startup_seconds: list[float] = field(default_factory=list)
    retried: list[str] = field(default_factory=list)
    start_wall: float = 0.0

    def start(self) -> None:
        """Start the workers and their painters; raises what a painter that cannot start raises."""
        t0 = time.perf_counter()
        self._start()
        self.start_wall = time.perf_counter() - t0

    def _start(self) -> None:
        """What :meth:`start` does (timed by it)."""

    def map(self, chunks: Iterable[Sequence[Item]], *, ordered: bool = False,
            encode: bool = False) -> Iterator[tuple[int, list[Any]]]:
        """Paint each chunk; yields ``(chunk index, [array or PNG bytes per item])``."""
        raise NotImplementedError

    def close(self) -> None:
        """Stop the workers (at once, when an error or Ctrl-C ends the run)."""

    def chunk_size(self, n_items: int) -> int:
        return chunk_size(n_items, self.n_workers)

    def summary(self) -> dict[str, Any]:
        """What ran where, for ``RenderResult`` (never in the manifest)."""
        return {"backend": type(self).__name__, "workers": self.n_workers,
                "start_wall": round(self.start_wall, 3),
                "startup_seconds": [round(s, 3) for s in self.startup_seconds], "retried": list(self.retried)}

    def __enter__(self) -> Runner:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class SerialRunner(Runner):
    """The :class:`Runner` interface on a painter in this process."""

    painter: Any = None

    def chunk_size(self, n_items: int) -> int:
        """One image a chunk: nothing is spread, and a chunk's images are all held until it ends
        (8 of 1200x900 were 35 MB of a run's peak memory)."""
        return 1

    def _start(self) -> None:
        t0 = time.perf_counter()
        self.painter.load()
        self.startup_seconds = [time.perf_counter() - t0]

    def map(self, chunks: Iterable[Sequence[Item]], *, ordered: bool = False,
            encode: bool = False) -> Iterator[tuple[int, list[Any]]]:
        for index, chunk in enumerate(chunks):
            yield index, paint_items(self.painter, chunk, encode)

    def close(self) -> None:
        self.painter.close()


def paint_all(runner: Runner, items: Sequence[Item], bar: Any = None) -> list[NDArray[Any]]:
    """Paint `items` with `runner`: RGBA uint8 arrays of shape (h, w, 4), in the order of `items`.

    `bar` (a tqdm progress bar) advances by each finished chunk's images.
    """
    size = runner.chunk_size(len(items))
    out: list[Any] = [None] * len(items)
    for index, results in runner.map(chunked(items, size), encode=False):
        out[index * size:index * size + len(results)] = results
        if bar is not None:
            bar.update(len(results))
    return out


# -- local processes ---------------------------------------------------------------------
_PROCESS_PAINTER: WarmPainter | None = None


def prepare_worker(threads: int) -> None:
    """Get a fresh worker process ready for Blender: its thread count, and a clean ``sys.path``.

    ``LP_NUM_THREADS`` (Mesa llvmpipe reads it when GL starts) is set unless
    the user set it. A process spawned by one that had imported ``bpy``
    inherits Blender's own script folders on ``sys.path``, where a ``bpy``
    package would shadow the ``bpy`` module; they are removed (Blender adds
    them back when it loads). The PNG encoder is imported now, before Blender.
    """
    os.environ.setdefault("LP_NUM_THREADS", str(threads))
    forget_blender_paths()
    from brainpainter.io.output import load_encoder

    load_encoder()  # the PNG encoder imports slowly once bpy is loaded


def forget_blender_paths() -> None:
    """Remove Blender's script folders from ``sys.path`` in a process that has not loaded bpy.

    ``import bpy`` puts ``bpy/<version>/scripts/startup`` and ``.../modules`` first on
    ``sys.path``, and a process spawned by one that had imported it starts with that path
    (multiprocessing passes it on), where the ``bpy`` package of the scripts shadows the ``bpy``
    module: ``No module named '_bpy'``. Blender adds them back when it loads.
    """
    if "bpy" not in sys.modules:
        marker = f"{os.sep}bpy{os.sep}"
        sys.path[:] = [p for p in sys.path if marker not in os.path.join(str(p), "")]


def worker_temp(base: str) -> None:
    """Put this worker's temporary files (Blender's ``blender_*`` session folder) in a folder in `base`.

    Blender removes that folder only on a normal exit; a terminated worker left one behind per run.
    `base` belongs to whoever started the worker, and is removed by it. No effect once bpy is loaded.
    """
    if "bpy" not in sys.modules:
        os.makedirs(base, exist_ok=True)
        os.environ["TMPDIR"] = tempfile.tempdir = tempfile.mkdtemp(prefix="worker-", dir=base)


def _init_process(spec: PainterSpec, threads: int, temp: str | None = None) -> None:
    """Pool worker start: renderer threads set before Blender loads; Ctrl-C left to the parent."""
    import signal

    global _PROCESS_PAINTER
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops the pool on Ctrl-C
    if temp is not None:
        worker_temp(temp)
    prepare_worker(threads)
    _PROCESS_PAINTER = WarmPainter(spec)


def _process_warm() -> tuple[int, float]:
    assert _PROCESS_PAINTER is not None
    _PROCESS_PAINTER.get()
    return os.getpid(), _PROCESS_PAINTER.load_seconds


def _process_paint(items: Sequence[Item], encode: bool) -> list[Any]:
    assert _PROCESS_PAINTER is not None
    return paint_items(_PROCESS_PAINTER.get(), items, encode)


@dataclass
class LocalRunner(Runner):
    """A pool of `n_workers` processes on this machine, each with a warm painter.

    Parameters
    ----------
    spec : PainterSpec
    n_workers : int
    threads : int, optional
        Renderer threads per worker (``LP_NUM_THREADS``, unless already set);
        default: the cores divided among the workers.
    """

    spec: PainterSpec | None = None
    threads: int | None = None
    _pool: Any = field(default=None, init=False, repr=False)
    _temp: str | None = field(default=None, init=False, repr=False)

    def _start(self) -> None:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        threads = self.threads or render_threads(self.n_workers)
        self._temp = tempfile.mkdtemp(prefix="brainpainter-jobs-")  # the workers' temporary files
        # spawn: a fresh interpreter per worker; forking a process with Blender loaded is unsafe.
        self._pool = ProcessPoolExecutor(
            self.n_workers, mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_process,  # type: ignore[arg-type]
            initargs=(self.spec, threads, self._temp))  # type: ignore[arg-type]
        try:
            warm = [self._pool.submit(_process_warm) for _ in range(self.n_workers)]
            loads = {pid: seconds for pid, seconds in (f.result() for f in warm)}
        except BaseException:
            self.close(abort=True)
            raise
        self.startup_seconds = list(loads.values())

    def map(self, chunks: Iterable[Sequence[Item]], *, ordered: bool = False,
            encode: bool = False) -> Iterator[tuple[int, list[Any]]]:
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        def collect(future: Any, chunk: Sequence[Item]) -> Any:
            try:
                return future.result()
            except BrokenProcessPool:
                raise BrainPainterError(
                    f"a worker process of --jobs {self.n_workers} died (out of memory?); run again with "
                    "fewer --jobs or a smaller --size."
                ) from None

        try:
            yield from drive(chunks, lambda chunk: self._pool.submit(_process_paint, chunk, encode),
                              lambda fs: wait(fs, return_when=FIRST_COMPLETED).done, collect,
                              window=2 * self.n_workers + 2, ordered=ordered)
        except BaseException:
            self.close(abort=True)
            raise

    def close(self, abort: bool = False) -> None:
        try:
            self._stop(abort)
        finally:
            temp, self._temp = self._temp, None
            if temp is not None:  # the workers are gone: their blender_* folders go too
                shutil.rmtree(temp, ignore_errors=True)

    def _stop(self, abort: bool) -> None:
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if not abort:
            pool.shutdown(wait=True)
            return
        # Ctrl-C or an error: drop queued work and stop every worker now, not after its chunk.
        terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
        if terminate is not None:
            terminate()
            return
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for p in processes:
            p.terminate()
        for p in processes:
            p.join(10)
