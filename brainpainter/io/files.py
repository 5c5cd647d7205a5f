"""The one way input files are opened: regular files only, with a size limit.

Every path a user gives (tables, region-group configs, label maps, template
and subject files) goes through :func:`read_input` (read it, bounded) or
:func:`check_input` (check it before a library reads it by path). Both:

* refuse what is not a regular file (a folder, ``/dev/zero``, a FIFO, a
  socket) without blocking: the file is opened with ``O_NONBLOCK`` and
  checked with ``fstat``, so a named pipe with no writer cannot hang the run;
* refuse files larger than a limit before reading them (checked with
  ``fstat``; reading stops at the limit in case the file grows meanwhile);
* turn OS errors into one line that names the file and says what to do.
"""

from __future__ import annotations

import errno
import os
import stat
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError

#: Size limits in bytes per kind of input (tables: :func:`brainpainter.io.rawtable.max_bytes`).
LIMITS = {
    "atlas config": 1 * 2**20,
    "label map": 256 * 2**20,
    "subject file": 1024 * 2**20,
    "template file": 1024 * 2**20,
}
#: Inflated bytes :func:`inflated` shows a format's `used` to learn the size of its data.
HEAD_BYTES = 4096
#: Largest data file read (a map, a GIfTI), and largest size a gzipped one may inflate to (bytes).
MAX_DATA_FILE = 1024 * 2**20


def _open(path: Path, what: str, hint: str) -> int:
    name = str(path)
    if not name or name == ".":
        raise BrainPainterError(f"{what} path is empty; {hint or 'give the path of a file'}.")
    try:
        return os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise BrainPainterError(f"{what} {name!r} does not exist; {hint or 'check the path'}.") from None
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            raise BrainPainterError(f"{what} path {name[:80]!r}... is too long; check the path.") from None
        raise BrainPainterError(f"cannot read {what} {name!r} ({exc.strerror or exc}); check the path and "
                                "permissions.") from None


def _check_fd(fd: int, path: Path, what: str, limit: int, hint: str, env: str = "") -> int:
    st = os.fstat(fd)
    if stat.S_ISDIR(st.st_mode):
        raise BrainPainterError(f"{what} {str(path)!r} is a folder; {hint or 'give the path of a file'}.")
    if not stat.S_ISREG(st.st_mode):
        kind = ("a named pipe (FIFO)" if stat.S_ISFIFO(st.st_mode) else
                "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else
                "a socket" if stat.S_ISSOCK(st.st_mode) else "not a file")
        raise BrainPainterError(f"{what} {str(path)!r} is not a regular file ({kind}); "
                                f"{hint or 'give the path of a file'}.")
    if st.st_size > limit:
        raise too_big(what, str(path), st.st_size, limit, env)
    return st.st_size


def too_big(what: str, name: str, size: int, limit: int, env: str = "") -> BrainPainterError:
    """The error for an input over its size limit."""
    raise_hint = f", or raise the limit with {env}" if env else ""
    return BrainPainterError(
        f"{what} {name!r} is {size / 2**20:.1f} MB; at most {limit / 2**20:.0f} MB is read, to keep memory "
        f"bounded. Check that it is the right file{raise_hint}."
    )


def read_input(path: str | os.PathLike[str], what: str = "input", limit: int | None = None,
               hint: str = "", env: str = "") -> bytes:
    """The bytes of a regular file of at most `limit` bytes.

    Parameters
    ----------
    path : path-like
    what : str
        What the file is, for messages (``"atlas config"``); also picks the
        default limit from :data:`LIMITS`.
    limit : int, optional
        Size limit in bytes.
    hint : str
        What to do, appended to messages.
    env : str
        Environment variable that raises the limit, named in the message.

    Raises
    ------
    BrainPainterError
        Missing, not a regular file, too large or unreadable.
    """
    path = Path(path)
    limit = LIMITS.get(what, 64 * 2**20) if limit is None else limit
    fd = _open(path, what, hint)
    try:
        _check_fd(fd, path, what, limit, hint, env)
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
    except OSError as exc:
        raise BrainPainterError(f"cannot read {what} {str(path)!r} ({exc.strerror or exc}); check the "
                                "file.") from None
    finally:
        os.close(fd)
    if total > limit:
        raise too_big(what, str(path), total, limit, env)
    return b"".join(chunks)


def check_input(path: str | os.PathLike[str], what: str = "input", limit: int | None = None,
                hint: str = "") -> Path:
    """Check that `path` is a regular file within `limit` bytes, for a library that reads it by path."""
    path = Path(path)
    limit = LIMITS.get(what, 64 * 2**20) if limit is None else limit
    fd = _open(path, what, hint)
    try:
        _check_fd(fd, path, what, limit, hint)
    finally:
        os.close(fd)
    return path


def check_input_dir(path: str | os.PathLike[str], what: str = "folder", hint: str = "") -> Path:
    """Check that `path` is an existing folder."""
    path = Path(path)
    name = str(path)
    if not name:
        raise BrainPainterError(f"{what} path is empty; {hint or 'give a folder'}.")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise BrainPainterError(f"{what} {name!r} does not exist; {hint or 'check the path'}.") from None
    except OSError as exc:
        raise BrainPainterError(f"cannot open {what} {name[:200]!r} ({exc.strerror or exc}); check the "
                                "path.") from None
    if not stat.S_ISDIR(st.st_mode):
        raise BrainPainterError(f"{what} {name!r} is not a folder; {hint or 'give a folder'}.")
    return path


def inflated(raw: bytes, what: str, limit: int | None = None,
             used: Callable[[bytes], int | None] | None = None) -> bytes:
    """`raw`, or if it is gzip-compressed (by its magic number), its contents, at most `limit` bytes
    (default :data:`MAX_DATA_FILE`).

    Parameters
    ----------
    raw : bytes
    what : str
        The file, for messages.
    limit : int, optional
    used : callable, optional
        ``used(head)``: how many bytes the file's format uses, from its first :data:`HEAD_BYTES` inflated
        bytes (None: all); inflating stops there, so that trailing bytes (1 GiB of zeros after an
        ``.mgz``'s data) are never held in memory.

    Raises
    ------
    BrainPainterError
        Inflating to more than `limit` bytes, or broken or cut-short gzip data.
    """
    if raw[:2] != b"\x1f\x8b":
        return raw
    limit = MAX_DATA_FILE if limit is None else limit
    d = zlib.decompressobj(wbits=31)
    try:
        if used is not None:
            head = d.decompress(raw, HEAD_BYTES)
            need = used(head)
            if need is not None and need <= limit:
                return _inflated_to(d, head, need, what)
            d = zlib.decompressobj(wbits=31)
        out = d.decompress(raw, limit + 1)
    except zlib.error as exc:
        raise BrainPainterError(f"{what} is not readable gzip data ({exc}); give the file as your software "
                                "wrote it.") from None
    if len(out) > limit:
        raise BrainPainterError(f"{what} inflates to more than {limit >> 20} MB; at most that much is read, "
                                "to keep memory bounded. Check that it is the right file.")
    if not d.eof:
        raise BrainPainterError(f"{what} is cut short (its gzip data end early); give the whole file.")
    return out


def _inflated_to(d: Any, head: bytes, need: int, what: str) -> bytes:
    """`head` and the next bytes of decompressor `d`, `need` bytes in all (fewer where the data end)."""
    parts, have = [head], len(head)
    while have < need and not d.eof:
        chunk = d.decompress(d.unconsumed_tail, min(need - have, 1 << 24))
        if not chunk and not d.unconsumed_tail:
            break
        parts.append(chunk)
        have += len(chunk)
    if have < need and not d.eof:
        raise BrainPainterError(f"{what} is cut short (its gzip data end early); give the whole file.")
    return b"".join(parts)[:need]
