"""Access to Blender's Python module: import on use, a lean or a full start, quiet calls.

``bpy`` holds one Blender per process; everything that touches it goes
through :data:`LOCK` so renderers can be shared by threads (a web server).

Blender starts in one of two ways (:func:`import_bpy`):

- ``import_bpy(full=False)``, the lean start of the ``gpu`` draw path (which uses its
  own render engine and scene, ``bpy.ops.render.render`` and ``gpu``; nothing else):
  Blender without its Python UI scripts (``bpy.utils.load_scripts``: 2,486 classes,
  then the add-ons, Cycles among them) and without the factory reset (which loads
  the add-ons again): ~0.2 s less of a first image. A :data:`sys.meta_path` finder,
  there only during ``import bpy`` and gone once ``bpy.utils`` is imported, makes
  ``bpy.utils.load_scripts`` and ``bpy.utils.load_scripts_extensions`` record
  Blender's calls instead of running them; both are put back when the import returns.
- ``import_bpy()`` (``full=True``), for everything else (Cycles, other ``bpy.ops``,
  ``bpy.data`` beyond the ``gpu`` engine's scene, other plugins): after a lean start
  the recorded calls run as Blender would have run them, then the factory reset,
  once. The reset deletes every scene; :mod:`~brainpainter_blender.gpu_context`
  makes its own again.

Where ``bpy`` was already imported (inside the Blender application, or by the
caller) or ``bpy.app.background`` is false, nothing is skipped; the factory reset
runs in background mode only (never on a user's scene in the Blender application).
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import importlib.abc
import importlib.machinery
import os
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator, Sequence
from types import ModuleType
from typing import IO, Any

from brainpainter.errors import BrainPainterError
from brainpainter.io.interrupts import held

#: The bpy releases brainpainter is tested with, per Python (the same pins as pyproject.toml's
#: dependencies; tests/test_renderer_blender.py checks they agree).
TESTED_BPY = {(3, 11): ">=4.2,<5.1", (3, 13): ">=5.2,<5.4"}

#: Serialises every use of bpy in this process (Blender is not thread-safe).
LOCK = threading.RLock()
_state: dict[str, object] = {}


def import_bpy(full: bool = True) -> ModuleType:
    """Import ``bpy``: Blender's whole start, or the lean start of the gpu draw path.

    Parameters
    ----------
    full : bool
        True: Blender's UI scripts and add-ons loaded (Cycles) and, in background
        mode, reset to an empty factory scene; once per process, completing a lean
        start when first asked. False: the lean start (module docstring), if this
        call imports ``bpy``; enough for :func:`~brainpainter_blender.gpu_context.in_gpu_context`.

    Raises
    ------
    BrainPainterError
        If Blender's Python module cannot be imported.
    """
    bpy = _state.get("bpy")
    if bpy is not None and not (full and "deferred" in _state):
        return bpy  # type: ignore[return-value]
    with LOCK:
        if "bpy" not in _state:
            _state["bpy"] = _import(lean=not full)
        deferred = _state.pop("deferred", None) if full else None
        if deferred is not None:
            _complete(_state["bpy"], deferred)  # type: ignore[arg-type]
        return _state["bpy"]  # type: ignore[return-value]


class _DeferScripts(importlib.abc.MetaPathFinder):
    """During ``import bpy``: ``bpy.utils.load_scripts{,_extensions}`` record their calls.

    Finds nothing itself: at the import of ``bpy.utils`` it leaves :data:`sys.meta_path`
    and wraps that module's loader for its one execution.
    """

    def __init__(self) -> None:
        self.utils: ModuleType | None = None
        self.real: dict[str, Callable[..., None]] = {}
        self.calls: list[tuple[Callable[..., None], dict[str, Any]]] = []

    def find_spec(self, name: str, path: Sequence[str] | None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        if name != "bpy.utils":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        loader: Any = spec.loader if spec is not None else None
        if loader is None or not hasattr(loader, "exec_module"):
            return spec

        def exec_module(module: ModuleType) -> None:
            del loader.exec_module  # the loader's own method again
            loader.exec_module(module)
            self.utils = module
            for fn in ("load_scripts", "load_scripts_extensions"):
                self.real[fn] = getattr(module, fn)
                setattr(module, fn, self._recorder(self.real[fn]))

        loader.exec_module = exec_module
        return spec

    def _recorder(self, real: Callable[..., None]) -> Callable[..., None]:
        def record(**kwargs: Any) -> None:
            if sys.modules["_bpy"].app.background:
                self.calls.append((real, kwargs))
            else:  # the Blender application: skip nothing
                real(**kwargs)
        return record

    def restore(self) -> None:
        """Leave :data:`sys.meta_path` (if never found) and put ``bpy.utils``'s functions back."""
        with contextlib.suppress(ValueError):
            sys.meta_path.remove(self)
        for fn, real in self.real.items():
            setattr(self.utils, fn, real)


def _import(lean: bool) -> ModuleType:
    """``import bpy`` with its output and signals held; ``lean``: its scripts left to :func:`_complete`."""
    defer = _DeferScripts() if lean and "bpy" not in sys.modules else None
    if defer is not None:
        sys.meta_path.insert(0, defer)
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
    finally:
        if defer is not None:
            defer.restore()
    if defer is not None and defer.calls:
        _state["deferred"] = defer.calls
    elif bpy.app.background:  # never wipe a user's scene inside the Blender application
        with quiet(), held():
            bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy  # type: ignore[no-any-return]


def _complete(bpy: ModuleType, calls: list[tuple[Callable[..., None], dict[str, Any]]]) -> None:
    """Finish a lean start: Blender's recorded script loading, then the factory reset."""
    with quiet(), held():
        for real, kwargs in calls:
            real(**kwargs)
        bpy.ops.wm.read_factory_settings(use_empty=True)


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
    bpy = import_bpy(full=False)
    tested = TESTED_BPY.get(sys.version_info[:2])
    name = f"Blender {bpy.app.version_string} (bpy)"
    if tested is None:
        return name, "bpy is tested on Python 3.11 and 3.13 only"
    py = "{}.{}".format(*sys.version_info[:2])
    return name, (f"brainpainter is tested with bpy{tested} on Python {py}; "
                  f"install one with: pip install 'bpy{tested}'")
