"""Render on a ``dask.distributed`` cluster: a worker plugin holding warm painters, and a runner.

Imported only when a run is given a Dask client or scheduler address (it
imports ``distributed``); see :mod:`brainpainter.rendering.parallel` for the design.
A :class:`PainterPlugin` is registered once per run, so every worker (also
one that joins or is restarted later) builds its painter once; tasks carry
colours and views, and return PNG bytes. Tasks that raise are retried (and
reported on stderr); tasks of a worker that dies are rescheduled by Dask.
"""

from __future__ import annotations

import os
import sys
import time
import uuid
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from distributed import get_worker, wait
from distributed.diagnostics.plugin import WorkerPlugin

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.options import import_distributed
from brainpainter.rendering.parallel import (
    RETRIES,
    WORKER_WAIT_S,
    Item,
    PainterSpec,
    Retry,
    Runner,
    WarmPainter,
    chunk_size,
    decode_png,
    drive,
    paint_items,
    prepare_worker,
    worker_temp,
)

if TYPE_CHECKING:  # pragma: no cover
    from brainpainter.rendering.painter import Painter


class PainterPlugin(WorkerPlugin):
    """A Dask worker plugin holding the warm painter of one run's spec on every worker.

    Registered once per run; Dask also sets it up on workers that join (or are
    restarted) later. ``setup`` fixes the renderer threads before Blender
    loads; the painter itself loads with the first task (in a task thread, as
    every later render); ``teardown`` (unregistering at the end of the run)
    closes it.

    Parameters
    ----------
    spec : PainterSpec
    threads : int
        Renderer threads per worker (``LP_NUM_THREADS``, unless set); one
        worker process per core with 1 thread is the fastest layout.
    """

    def __init__(self, spec: PainterSpec, threads: int = 1) -> None:
        self.spec = spec
        self.threads = threads
        self.name = f"brainpainter-{spec.token}-{uuid.uuid4().hex[:8]}"  # one per run, even of one spec
        self.warm: WarmPainter | None = None

    def setup(self, worker: Any) -> None:
        local = getattr(worker, "local_directory", None)
        if local:  # Dask removes the worker's folder when it closes, also after a kill of the worker
            worker_temp(os.path.join(local, "brainpainter-tmp"))
        prepare_worker(self.threads)
        self.warm = WarmPainter(self.spec)

    def teardown(self, worker: Any) -> None:
        if self.warm is not None:
            self.warm.close()

    def painter(self) -> Painter:
        if self.warm is None:  # not set up: only when called outside a worker
            self.warm = WarmPainter(self.spec)
        return self.warm.get()


def _dask_plugin(name: str) -> PainterPlugin:
    plugin = get_worker().plugins.get(name)
    if not isinstance(plugin, PainterPlugin):
        raise RuntimeError(f"worker plugin {name!r} is not registered on this worker")
    return plugin


def _dask_warm(name: str) -> tuple[str, int, float]:
    plugin = _dask_plugin(name)
    plugin.painter()
    assert plugin.warm is not None
    return get_worker().address, os.getpid(), plugin.warm.load_seconds


def _dask_paint(name: str, items: Sequence[Item]) -> list[bytes]:
    return paint_items(_dask_plugin(name).painter(), items, encode=True)


def check_address(address: object) -> None:
    """Refuse a scheduler address (``--scheduler``, ``BRAINPAINTER_SCHEDULER``) without host and port.

    ``nan``, ``-1`` or ``host`` would otherwise make Dask retry for 30 s and print a traceback.
    """
    from urllib.parse import urlsplit

    if not isinstance(address, str):
        return
    text = address.strip() if "://" in address else "tcp://" + address.strip()
    parts = urlsplit(text)
    if parts.scheme not in ("tcp", "tls", "ws", "wss"):
        return  # inproc://, ucx://...: Dask checks them
    try:
        port = parts.port
    except ValueError:
        port = None
    if not parts.hostname or port is None:
        raise BrainPainterError(
            f"the Dask scheduler address {address[:80]!r} (--scheduler or BRAINPAINTER_SCHEDULER) is not "
            "host:port; give e.g. tcp://host:8786, or unset BRAINPAINTER_SCHEDULER to render here."
        )


def _describe(chunk: Sequence[Item]) -> str:
    names = [item.label or str((item.metadata or {}).get("brainpainter:image", "?")) for item in chunk]
    return ", ".join(dict.fromkeys(names))


@dataclass
class DaskRunner(Runner):
    """Paint on a ``dask.distributed`` cluster.

    Parameters
    ----------
    spec : PainterSpec
    client : distributed.Client, optional
        An existing client (left open); or
    address : str, optional
        A scheduler address (``tcp://host:8786``); the client made for it is closed at the end.
    retries : int
        Times a failed task is sent again (a :class:`BrainPainterError`, the
        user's error, is not retried).
    threads : int
        Renderer threads per worker process.
    """

    spec: PainterSpec | None = None
    client: Any = None
    address: str | None = None
    retries: int = RETRIES
    threads: int = 1
    _own_client: bool = field(default=False, init=False, repr=False)
    _plugin: str | None = field(default=None, init=False, repr=False)
    _futures: list[Any] = field(default_factory=list, init=False, repr=False)

    def _start(self) -> None:
        distributed = import_distributed()
        assert self.spec is not None
        if self.client is None:
            check_address(self.address)
            try:
                self.client = distributed.Client(self.address, timeout="15s", set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise BrainPainterError(
                    f"cannot reach the Dask scheduler at {self.address!r} ({exc}); check the address "
                    "(e.g. tcp://host:8786) and that the scheduler is running."
                ) from None
            self._own_client = True
        try:
            workers = self.client.nthreads()  # {address: threads} of every worker
            if not workers:
                try:
                    self.client.wait_for_workers(1, timeout=WORKER_WAIT_S)
                except TimeoutError:
                    raise BrainPainterError(
                        f"the Dask cluster has no workers after {WORKER_WAIT_S:g} s; start some (e.g. "
                        "cluster.scale(8)) and run again."
                    ) from None
                workers = self.client.nthreads()
            plugin = PainterPlugin(self.spec, self.threads)
            self.client.register_plugin(plugin, name=plugin.name)
            self._plugin = plugin.name
            # One warm-up per worker: a painter that cannot start fails before any output exists.
            warm = [self.client.submit(_dask_warm, plugin.name, workers=[addr], allow_other_workers=True,
                                       pure=False) for addr in workers]
            done = self.client.gather(warm)
        except BaseException:
            self.close()
            raise
        self.n_workers = max(1, len(self.client.nthreads()))
        self.startup_seconds = [seconds for _, _, seconds in done]

    def map(self, chunks: Iterable[Sequence[Item]], *, ordered: bool = False,
            encode: bool = False) -> Iterator[tuple[int, list[Any]]]:
        assert self._plugin is not None
        attempts: dict[Any, int] = {}

        def submit(chunk: Sequence[Item], attempt: int = 0) -> Any:
            future = self.client.submit(_dask_paint, self._plugin, list(chunk), pure=False)
            attempts[future] = attempt
            self._futures.append(future)
            return future

        def collect(future: Any, chunk: Sequence[Item]) -> Any:
            attempt = attempts.pop(future, 0)
            self._futures.remove(future)
            if future.status == "finished":
                data = future.result()
                return data if encode else [decode_png(d) for d in data]
            exc = future.exception()
            if isinstance(exc, BrainPainterError):
                raise exc
            where = f"images {_describe(chunk)}"
            if attempt >= self.retries:
                raise BrainPainterError(
                    f"painting {where} failed {attempt + 1} times on the Dask cluster "
                    f"({type(exc).__name__}: {exc}); see the workers' logs."
                )
            line = (f"{where}: {type(exc).__name__}: {exc}; retrying ({attempt + 1} of {self.retries})")
            self.retried.append(line)
            print(f"brainpainter: {line}", file=sys.stderr)
            return Retry(submit(chunk, attempt + 1))

        def wait_any(futures: list[Any]) -> Iterable[Any]:
            with self.client.as_current():  # wait() uses the current client; ours need not be the default
                done: Iterable[Any] = wait(  # type: ignore[no-untyped-call]
                    futures, return_when="FIRST_COMPLETED").done
                return done

        asked = [time.monotonic()]

        def window() -> int:
            """Two tasks per worker in flight; workers that join later (cluster.scale) get work too."""
            if time.monotonic() - asked[0] > 2.0:
                asked[0] = time.monotonic()
                self.n_workers = max(1, len(self.client.nthreads()))
            return 2 * self.n_workers + 2

        try:
            yield from drive(chunks, submit, wait_any, collect, window=window, ordered=ordered)
        except BaseException:
            if self._futures:
                self.client.cancel(self._futures)  # queued tasks go; running ones end with their chunk
            raise

    def chunk_size(self, n_items: int) -> int:
        return chunk_size(n_items, self.n_workers, largest=16)

    def close(self) -> None:
        client, self._futures = self.client, []
        if client is None:
            return
        try:
            if self._plugin is not None and client.status == "running":
                client.unregister_worker_plugin(self._plugin)  # closes the painters
        except Exception:  # a cluster that went away needs no clean-up
            pass
        finally:
            self._plugin = None
            if self._own_client:
                client.close()
                self.client = None
