"""Output folders: creating them, locking them, staging inside them, one-line OS errors.

The lock is ``flock`` on the folder itself (no lock file is left behind; the
kernel drops it when the process dies, even on ``kill -9``). Staging folders
(:data:`STAGE_PREFIX`) live inside the output folder, on the same file
system, so publishing is a rename; one left by a killed run is removed by the
next run that takes the lock (:func:`remove_stale_stages`).

OS errors become one-line :class:`~brainpainter.errors.BrainPainterError`
messages through :func:`os_error` (full disk, read-only file system, name too
long, permission denied...).
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from brainpainter.errors import BrainPainterError

STAGE_PREFIX = ".brainpainter-staging-"

_ERRNO_HINTS = {
    errno.ENOSPC: "the disk is full; free some space or choose another place",
    errno.EROFS: "the file system is read-only; choose a writable place",
    errno.ENAMETOOLONG: "a file or folder name is too long; choose a shorter name",
    errno.EACCES: "permission denied; choose a folder you can write to",
    errno.EPERM: "operation not permitted; choose a folder you can write to",
    errno.EDQUOT: "the disk quota is exceeded; free some space or choose another place",
    errno.EPIPE: "the output pipe was closed",
    errno.ENOTDIR: "a part of the path is a file, not a folder; choose another path",
    errno.EISDIR: "it is a folder; give a file path",
    errno.EEXIST: "it exists already; choose another name",
    errno.ELOOP: "too many symbolic links; choose another path",
    errno.EIO: "input/output error on the device; check the disk",
}


def os_error(exc: OSError, action: str, path: str | os.PathLike[str] | None = None) -> BrainPainterError:
    """A one-line error for an OS error while doing `action` (e.g. ``"cannot write"``) on `path`."""
    target = exc.filename if path is None else path
    where = f" {str(target)[:160]!r}" if target is not None else ""
    hint = _ERRNO_HINTS.get(exc.errno or 0, exc.strerror or type(exc).__name__)
    err = BrainPainterError(f"{action}{where}: {hint}.")
    err.errno = exc.errno  # type: ignore[attr-defined]
    return err


# -- locking ---------------------------------------------------------------------------
@contextmanager
def folder_lock(folder: Path, what: str = "output folder") -> Iterator[None]:
    """Hold an exclusive lock on `folder` (which must exist) for the ``with`` block.

    Raises
    ------
    BrainPainterError
        Another process holds the lock.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: no flock; documented in docs/reliability.md
        yield
        return
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError as exc:
        raise os_error(exc, f"cannot open {what}", folder) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise BrainPainterError(
                f"{what} {str(folder)!r} is in use by another brainpainter run; wait for it to finish or "
                "choose another output."
            ) from None
        yield
    finally:
        os.close(fd)  # releases the lock


def make_folder(folder: Path, what: str = "output folder", created: list[Path] | None = None) -> Path:
    """Create `folder` (and parents); a one-line error when that is impossible.

    Folders made are appended to `created` (outermost first); on failure the
    ones made so far are removed again.
    """
    folder = Path(folder)
    if str(folder) in ("", "."):
        folder = Path.cwd()
    made: list[Path] = []
    try:
        if folder.is_dir():
            return folder
        if folder.exists() or folder.is_symlink():
            raise BrainPainterError(f"{what} {str(folder)!r} exists and is not a folder; give a folder path.")
        missing = [folder]
        while not missing[-1].parent.exists() and missing[-1].parent != missing[-1]:
            missing.append(missing[-1].parent)
        for p in reversed(missing):
            p.mkdir()
            made.append(p)
    except OSError as exc:
        remove_empty(made)
        raise os_error(exc, f"cannot create {what}", folder) from None
    if created is not None:
        created.extend(made)
    return folder


def remove_empty(folders: list[Path]) -> None:
    """Remove `folders` (innermost last in the list) where they are empty."""
    for p in reversed(folders):
        try:
            p.rmdir()
        except OSError:
            break


def remove_stale_stages(folder: Path) -> None:
    """Remove staging folders left in `folder` by runs that were killed (call with the lock held)."""
    try:
        stale = [p for p in folder.iterdir() if p.name.startswith(STAGE_PREFIX) and p.is_dir()]
    except OSError:
        return
    for p in stale:
        shutil.rmtree(p, ignore_errors=True)


def new_stage(folder: Path, what: str) -> Path:
    try:
        return Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=folder))
    except OSError as exc:
        raise os_error(exc, f"cannot write into {what}", folder) from None


def default_mode(path: Path) -> None:
    mask = os.umask(0o022)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


def fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
