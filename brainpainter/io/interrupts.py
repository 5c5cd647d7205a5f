"""Holding Ctrl-C and SIGTERM while a renderer, or a publish, is in a state it cannot be interrupted in.

The command line's guard turns SIGINT/SIGTERM into an exception so that
output is cleaned up. Python raises it in the main thread at the next Python
instruction, wherever that is: inside ``import bpy``, Blender runs its own
start-up scripts, and an exception raised there left Blender half-made (a
segmentation fault, or a later internal error). A renderer wraps such a
section in :func:`held`; a signal that arrives meanwhile is kept and
delivered again as soon as the section ends, so the run still stops, cleanly.
Publishing an output (:mod:`brainpainter.io.transaction`) is such a section
too, and :func:`published` then says whether this process's output is
complete, so that a signal after it is never reported as "nothing was published".

Blocking the signal (``pthread_sigmask``) is not enough: it only blocks it in
the calling thread, and another thread (a writer, a progress bar) receives it
and sets Python's flag all the same.

The state is guarded by a *re-entrant* lock: Python runs signal handlers in
the main thread between two instructions, so :func:`defer` (called by a
handler) can run while the main thread itself is inside :func:`held`'s
``with _LOCK`` block; with a plain lock it would wait for itself for ever.
Every value the handler can see there is consistent: the count changes in one
store, and a signal that finds the count at 0 is simply not deferred.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_LOCK = threading.RLock()  # re-entrant: see the module's docstring
_state = {"held": 0}
_pending: list[int] = []


@contextmanager
def held() -> Iterator[None]:
    """Keep SIGINT/SIGTERM handled by :func:`defer` for the duration; re-deliver them afterwards."""
    with _LOCK:
        _state["held"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _state["held"] -= 1
            again = _pending[:1] if _state["held"] == 0 else []
            if again:  # the first is delivered; a handler running now finds the count at 0 and raises
                _pending.clear()
        for signum in again:
            signal.raise_signal(signum)  # the handler runs now, outside the section


def defer(signum: int) -> bool:
    """Called by a signal handler: True when the signal was kept for later (a section is held)."""
    with _LOCK:
        if _state["held"] > 0:
            _pending.append(signum)
            return True
    return False


_published: list[str] = []


def mark_published(what: str) -> None:
    """Record that `what` (a folder or file) was published whole by this process."""
    _published.append(what)


def published() -> list[str]:
    """What this process has published whole (see :func:`mark_published`), oldest first."""
    return list(_published)
