"""Files kept between runs in the user's cache folder, each checked before it is trusted.

Start-up work that gives the same result every run (the plugins installed, compiled shaders) is
kept in ``<user cache>/brainpainter`` (``platformdirs``; ``~/.cache/brainpainter`` on Linux).
A command line run points ``XDG_CACHE_HOME`` at its private temporary folder
(:mod:`brainpainter.cli.guard`), so the folder is fixed before that, in :data:`CACHE_ENV`.
``BRAINPAINTER_CACHE=off`` turns every such cache off.

A cache file is one JSON document: the key it was made for (a digest of what the value depends
on), the value, and a SHA-256 of both. :func:`read` returns the value only when the file parses,
its digest matches and its key is the one asked for; anything else (a missing, corrupt, stale,
foreign or oversized file) reads as a miss, and the caller computes the value again and
:func:`write` replaces the file (atomically: a reader never sees half a file).
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

#: Environment variable holding the cache folder a run uses (set by the command line's guard).
CACHE_ENV = "BRAINPAINTER_CACHE_DIR"
#: ``BRAINPAINTER_CACHE=off`` (or ``0``, ``no``, ``false``): no cache is read or written.
SWITCH_ENV = "BRAINPAINTER_CACHE"
#: A cache file larger than this is not read (none of ours comes near it).
MAX_BYTES = 4 * 1024 * 1024


def enabled() -> bool:
    """Whether caches may be used (``BRAINPAINTER_CACHE`` is not off)."""
    return os.environ.get(SWITCH_ENV, "").strip().lower() not in {"off", "0", "no", "false"}


def cache_dir() -> Path | None:
    """The folder of brainpainter's caches (it may not exist yet); None when caches are off."""
    if not enabled():
        return None
    given = os.environ.get(CACHE_ENV)
    if given:
        return Path(given)
    if sys.platform == "linux":  # platformdirs' rule for Unix, without its import (~10 ms of --help)
        xdg = os.environ.get("XDG_CACHE_HOME", "").strip()
        return Path(xdg or os.path.expanduser("~/.cache")) / "brainpainter"
    import platformdirs

    return Path(platformdirs.user_cache_dir("brainpainter", appauthor=False))


def _digest(key: str, value: Any) -> str:
    import hashlib
    import json

    text = json.dumps([key, value], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def read(name: str, key: str) -> Any | None:
    """The value cached as `name` for `key`; None on any miss (absent, corrupt, stale, caches off).

    Parameters
    ----------
    name : str
        File name in :func:`cache_dir` (e.g. ``"entry-points.json"``).
    key : str
        What the value was made from (a digest); another key is a miss.
    """
    import json

    folder = cache_dir()
    if folder is None:
        return None
    try:
        with open(folder / name, "rb") as f:
            data = f.read(MAX_BYTES + 1)
        if len(data) > MAX_BYTES:
            return None
        doc = json.loads(data)
        if not isinstance(doc, dict) or doc.get("key") != key:
            return None
        value = doc.get("value")
        return value if doc.get("sha256") == _digest(key, value) else None
    except (OSError, ValueError, RecursionError):
        return None


def write(name: str, key: str, value: Any) -> None:
    """Cache `value` (JSON-able) as `name` for `key`; silently nothing when the folder is not writable."""
    import json

    folder = cache_dir()
    if folder is None:
        return
    doc = {"key": key, "value": value, "sha256": _digest(key, value)}
    write_atomic(folder / name, lambda f: f.write(json.dumps(doc, sort_keys=True).encode("utf-8")))


#: Cache files written while a command runs, by path: kept in memory until it succeeds (:func:`hold`).
_held: dict[Path, bytes] | None = None


#: Folders :func:`hold` made for the cache (deepest last), removed again by a failed command if empty.
_made: list[Path] = []


def hold() -> None:
    """Keep the cache files written from now on in memory until :func:`release` (a command line run:
    a command that fails writes nothing outside its output folder, not even a cache file).

    The cache folder itself is made now: Mesa writes its compiled shaders there only if it exists.
    """
    global _held
    _held = {}
    folder = cache_dir()
    _made.clear()
    if folder is not None:
        missing = [p for p in (folder, *folder.parents) if not p.exists()]
        try:
            folder.mkdir(parents=True, exist_ok=True)
            _made.extend(reversed(missing))
        except OSError:  # a read-only home: no cache
            pass


def release(keep: bool) -> None:
    """Write the cache files held since :func:`hold` if `keep` (the command succeeded); else forget
    them, and remove the folders :func:`hold` made where they are still empty."""
    global _held
    held, _held = _held or {}, None
    if keep:
        for path, data in held.items():
            write_atomic(path, functools.partial(_write_bytes, data))
        return
    for folder in reversed(_made):
        try:
            folder.rmdir()
        except OSError:  # not empty (Mesa's shaders of a run that failed late): a cache, kept
            break


def _write_bytes(data: bytes, f: IO[bytes]) -> None:
    f.write(data)


def write_atomic(path: Path, write: Callable[[IO[bytes]], object]) -> None:
    """Write `path` through `write(file)` into a temporary file beside it, then rename it into place
    (a reader never sees half a file); nothing where the folder cannot be written (a read-only or
    full disk: the next run computes the value again). While held (:func:`hold`), kept in memory."""
    import tempfile

    if _held is not None:
        import io

        buffer = io.BytesIO()
        write(buffer)
        _held[path] = buffer.getvalue()
        return

    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
        tmp = None
    except OSError:
        pass
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
