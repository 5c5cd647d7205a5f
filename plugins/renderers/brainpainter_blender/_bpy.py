"""Access to Blender's Python module: import on use, one factory reset, quiet calls.

``bpy`` holds one Blender per process; everything that touches it goes
through :data:`LOCK` so renderers can be shared by threads (a web server).
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import sys
import tempfile
import threading
from collections.abc import Iterator
from types import ModuleType
from typing import IO

from brainpainter.errors import BrainPainterError
from brainpainter.io.interrupts import held

#: The bpy releases brainpainter is tested with, per Python (the same pins as pyproject.toml's
#: dependencies; tests/test_renderer_blender.py checks they agree).
TESTED_BPY = {(3, 11): ">=4.2,<5.1", (3, 13): ">=5.2,<5.4"}

#: Serialises every use of bpy in this process (Blender is not thread-safe).
LOCK = threading.RLock()
_state: dict[str, object] = {}


def import_bpy() -> ModuleType:
    """Import ``bpy`` and reset Blender to an empty factory scene once per process.

    Raises
    ------
    BrainPainterError
        If Blender's Python module cannot be imported.
    """
    bpy = _state.get("bpy")
    if bpy is not None:
        return bpy  # type: ignore[return-value]
    with LOCK:
        if "bpy" in _state:
            return _state["bpy"]  # type: ignore[return-value]
        try:
            with quiet(), held():
                import bpy
        except ImportError as exc:
            reason = " ".join(str(exc).split())
            raise BrainPainterError(
                f"the Blender renderer needs Blender's Python module, which failed to import "
                f"({reason}); install it with 'pip install bpy' (bpy 4.2-5.0 needs Python 3.11, "
                f"bpy 5.2-5.3 Python 3.13)."
            ) from None
        if bpy.app.background:  # never wipe a user's scene inside the Blender application
            with quiet(), held():
                bpy.ops.wm.read_factory_settings(use_empty=True)
        _state["bpy"] = bpy
        return bpy


def _load_malloc_trim():
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
    except (OSError, AttributeError):  # not glibc (e.g. musl)
        return None


_malloc_trim = _load_malloc_trim()


def release_memory() -> None:
    """Give freed heap memory back to the system (glibc only; ~0.1 ms).

    Blender's draw code frees and reallocates large buffers whenever the set
    of visible objects changes; without trimming, glibc keeps the freed pages
    and a long-lived renderer's resident memory creeps up by ~0.3 MB per image.
    """
    if _malloc_trim is not None:
        _malloc_trim(0)


def _sink() -> IO[bytes]:
    """An anonymous file for captured output: in memory where Linux offers it.

    A temporary file on disk costs milliseconds to create on a busy disk,
    once per image (every GPU draw runs inside :func:`quiet`).
    """
    if hasattr(os, "memfd_create"):
        with contextlib.suppress(OSError):
            return os.fdopen(os.memfd_create("brainpainter-quiet", os.MFD_CLOEXEC), "w+b")
    return tempfile.TemporaryFile(mode="w+b")


@contextlib.contextmanager
def quiet() -> Iterator[list[str]]:
    """Silence Blender's C-level prints (``Saved: ...``, EGL notices) on fd 1 and 2.

    Yields a list that receives the captured text when the block ends, so a
    caller can add it to an error message.
    """
    captured: list[str] = []
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    fds = (1, 2)  # Blender's C code writes to the process's descriptors, whatever sys.stdout is
    with _sink() as sink:
        try:
            saved = [os.dup(fd) for fd in fds]
        except OSError:
            yield captured
            return
        try:
            for fd in fds:
                os.dup2(sink.fileno(), fd)
            yield captured
        finally:
            for fd, old in zip(fds, saved, strict=True):
                os.dup2(old, fd)
                os.close(old)
            sink.seek(0)
            captured.append(sink.read().decode("utf-8", "replace"))


def version_hint() -> tuple[str, str]:
    """The running Blender, and what to do when it misbehaves: ``("Blender 5.3.0 (bpy)", "install ...")``."""
    bpy = import_bpy()
    tested = TESTED_BPY.get(sys.version_info[:2])
    name = f"Blender {bpy.app.version_string} (bpy)"
    if tested is None:
        return name, "bpy is tested on Python 3.11 and 3.13 only"
    py = "{}.{}".format(*sys.version_info[:2])
    return name, (f"brainpainter is tested with bpy{tested} on Python {py}; "
                  f"install one with: pip install 'bpy{tested}'")
