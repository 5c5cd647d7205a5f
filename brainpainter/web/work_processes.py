"""The work a request causes (reading its upload into a run, a check report, a preview's colours, a job's
plan), run in processes that are killed past a time limit.

A thread cannot be stopped: a label map of thousands of long names laid out by matplotlib, or a hostile
upload that makes any reader slow, held one of the server's threads for minutes and kept the server
alive after SIGTERM. Here each of ``n`` long-lived threads owns one spawned process (started by that
thread, so the parent-death signal stays armed for the server's life: :func:`~brainpainter.web.worker.
die_with_parent`), hands it one call at a time through a pipe, and kills and replaces it when the call
takes longer than the limit; its data memory is bounded as a reading process's is. The caller's future
gets the call's result, its exception (pickled back), or :class:`WorkTooSlow`.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import pickle
import queue
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from brainpainter.errors import BrainPainterError

log = logging.getLogger(__name__)
#: A queued call: its future, the function, its positional and keyword arguments.
_Call = tuple[Future[Any], Callable[..., Any], tuple[Any, ...], dict[str, Any]]


class WorkTooSlow(BrainPainterError):
    """A request's work ran past the server's time limit; its process was killed."""


#: Seconds a new request process may take to import what the calls use.
STARTUP_S = 120.0
_STOPPING = BrainPainterError("the server is stopping; try again in a moment.")
_STOPPED = BrainPainterError("the work of this request stopped unexpectedly (too large for this server?); "
                             "give a smaller upload.")


class WorkProcesses:
    """`n` request processes, each run by its own thread; :meth:`submit` queues a call.

    Parameters
    ----------
    n : int
        Processes (calls run at once).
    time_limit_s : float
        Seconds one call may take; then its process is killed (and replaced) and the call fails.
    memory_bytes : int, optional
        Data memory of each process (``RLIMIT_DATA``; default a reading process's).
    """

    def __init__(self, n: int, time_limit_s: float, memory_bytes: int | None = None) -> None:
        self.n, self.time_limit_s, self.memory_bytes = max(1, n), time_limit_s, memory_bytes
        self._calls: queue.Queue[_Call | None] = queue.Queue()
        self._threads: list[threading.Thread] = []
        self._procs: dict[int, Any] = {}
        self._ctx = mp.get_context("spawn")
        self._stopping = threading.Event()

    def start(self) -> None:
        """Start the threads (each starts its process)."""
        for slot in range(self.n):
            thread = threading.Thread(target=self._serve, args=(slot,), name=f"brainpainter-work-{slot}",
                                      daemon=True)
            thread.start()
            self._threads.append(thread)

    def stop(self) -> None:
        """Kill the processes (a call in progress fails) and end the threads."""
        self._stopping.set()
        for _ in self._threads:
            self._calls.put(None)
        for proc in list(self._procs.values()):
            if proc.is_alive():
                proc.kill()
        for thread in self._threads:
            thread.join(timeout=5)
        self._threads.clear()

    def submit(self, func: Callable[..., Any], *args: Any, **kwargs: Any) -> Future[Any]:
        """Queue ``func(*args, **kwargs)`` (module-level `func`, picklable arguments and result)."""
        future: Future[Any] = Future()
        if self._stopping.is_set():
            future.set_exception(_STOPPING)
        else:
            self._calls.put((future, func, args, kwargs))
        return future

    def pids(self) -> list[int]:
        """The processes' ids (tests and benchmarks)."""
        return [p.pid for p in self._procs.values() if p.pid is not None]

    # -- one thread per process ------------------------------------------------------------------
    def _spawn(self, slot: int) -> Any:
        """A new process for `slot`, once it is ready (its imports done: they do not count against a
        call's time limit); its connection."""
        while True:
            parent, child = self._ctx.Pipe()
            proc = self._ctx.Process(target=work_main, args=(child, self.memory_bytes), daemon=True,
                                     name=f"brainpainter-work-{slot}")
            proc.start()
            child.close()
            self._procs[slot] = proc
            try:
                if parent.poll(STARTUP_S) and parent.recv() == "ready":
                    return parent
            except (EOFError, OSError):
                pass
            log.warning("a request process did not start in %g s; starting another", STARTUP_S)
            parent.close()
            proc.kill()
            proc.join(timeout=5)
            if self._stopping.is_set():
                return None

    def _replace(self, slot: int, conn: Any) -> Any:
        """Kill the slot's process; a new one, unless the server is stopping (then None)."""
        conn.close()
        proc = self._procs[slot]
        if proc.is_alive():
            proc.kill()
        proc.join(timeout=5)
        return None if self._stopping.is_set() else self._spawn(slot)

    def _serve(self, slot: int) -> None:
        conn = self._spawn(slot)
        while conn is not None and (item := self._calls.get()) is not None:
            future, func, args, kwargs = item
            if future.set_running_or_notify_cancel():
                conn = self._call(slot, conn, future, func, args, kwargs)
        if conn is not None:
            conn.close()

    def _call(self, slot: int, conn: Any, future: Future[Any], func: Callable[..., Any],
              args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
        """Run one call in the slot's process; its connection afterwards (a new process after a kill; None
        when the server stops)."""
        try:
            conn.send((func, args, kwargs))
        except (pickle.PicklingError, TypeError, AttributeError) as exc:  # a call that cannot be sent
            future.set_exception(exc)
            return conn
        except OSError:  # the process died between calls
            conn = self._replace(slot, conn)
            future.set_exception(_STOPPING if conn is None else _STOPPED)
            return conn
        if not conn.poll(self.time_limit_s):
            log.warning("request work %s took longer than %g s; its process was killed",
                        getattr(func, "__name__", func), self.time_limit_s)
            conn = self._replace(slot, conn)
            future.set_exception(_STOPPING if conn is None else WorkTooSlow(
                f"this request needed more than this server's limit of {self.time_limit_s:g} s of work; give "
                "a smaller upload (fewer labels, nodes or rows, shorter names) or fewer options, or run "
                "brainpainter on your own computer."))
            return conn
        try:
            status, payload = conn.recv()
        except (EOFError, OSError, pickle.UnpicklingError, AttributeError, TypeError):
            conn = self._replace(slot, conn)
            future.set_exception(_STOPPING if conn is None else _STOPPED)
            return conn
        if status == "ok":
            future.set_result(payload)
        else:
            future.set_exception(payload)
        return conn


def work_main(conn: Any, memory_bytes: int | None) -> None:
    """Entry point of a request process: run each call received, send ``("ok", result)`` or ``("error",
    exception)`` (an exception that cannot be pickled is sent as its one line)."""
    from brainpainter.web.worker import die_with_parent, limit_memory

    die_with_parent()
    limit_memory(memory_bytes)
    import brainpainter.web.options  # noqa: F401  (warm: the first call does not wait for the imports)

    conn.send("ready")
    while True:
        try:
            func, args, kwargs = conn.recv()
        except (EOFError, OSError):
            return
        try:
            answer: tuple[str, Any] = ("ok", func(*args, **kwargs))
        except MemoryError:
            answer = ("error", BrainPainterError("this request needs more memory than this server gives one "
                                                 "request; give a smaller upload."))
        except Exception as exc:
            answer = ("error", _sendable(exc))
        try:
            conn.send(answer)
        except (pickle.PicklingError, TypeError, AttributeError):  # a result that cannot be sent back
            conn.send(("error", RuntimeError(f"the answer of {getattr(func, '__name__', 'a call')} cannot be "
                                             "sent between processes")))


def _sendable(exc: Exception) -> Exception:
    """`exc` if it survives pickling, else a plain exception of the same kind and first line."""
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return BrainPainterError(text) if isinstance(exc, BrainPainterError) else RuntimeError(
            f"{type(exc).__name__}: {text}")
