"""Output transactions: lock the output folder, stage, verify, publish.

Every command that writes (``render``, ``figure``, ``movie``, ``atlas add``,
``template build``) goes through one of two context managers:

* :class:`FolderTransaction` for an output folder of several files plus a
  ``manifest.json`` (``render``);
* :class:`FileTransaction` for one output file (a figure, a movie).

Both take an exclusive, non-blocking lock on the output folder (``flock`` on
the folder itself, so no lock file is left behind; the kernel drops it when
the process dies, even on ``kill -9``), write into a hidden staging folder
inside it (same file system, so publishing is a rename), verify what was
written (PNG, GIF, MP4, TIFF, PDF and SVG structure and sizes), and only then
publish: the previous run's manifest is removed first, the files are renamed
into place, and the new manifest is written last, so a manifest is never left
describing files it did not make. Whatever happens (an error, Ctrl-C,
SIGTERM) the staging folder is removed; one left by a killed run is removed
by the next run that takes the lock.

:func:`replace_folder` publishes a whole folder built elsewhere (a template,
an atlas) in place of an old one, refusing to replace a folder this program
did not make.

OS errors become one-line :class:`~brainpainter.errors.BrainPainterError`
messages through :func:`os_error` (full disk, read-only file system, name too
long, permission denied...).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import struct
import tempfile
import zlib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError

STAGE_PREFIX = ".brainpainter-staging-"
MANIFEST = "manifest.json"

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


def os_error(exc: OSError, action: str, path: str | os.PathLike | None = None) -> BrainPainterError:
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


def _new_stage(folder: Path, what: str) -> Path:
    try:
        return Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=folder))
    except OSError as exc:
        raise os_error(exc, f"cannot write into {what}", folder) from None


def _default_mode(path: Path) -> None:
    mask = os.umask(0o022)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


def _fsync_dir(folder: Path) -> None:
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


# -- verification -------------------------------------------------------------------------
def verify_file(path: Path, size: tuple[int, int] | None = None, frames: int | None = None) -> None:
    """Check that `path` is a complete file of its format (by its ending), of `size` and `frames`.

    Parameters
    ----------
    path : Path
        ``.png``, ``.gif``, ``.mp4``, ``.tif``/``.tiff``, ``.pdf``, ``.svg`` or ``.json``.
    size : (width, height), optional
        Expected pixel size (PNG, GIF, TIFF).
    frames : int, optional
        Expected number of frames (GIF, MP4).

    Raises
    ------
    BrainPainterError
        The file is empty, truncated or not what was expected.
    """
    suffix = path.suffix.lower()
    try:
        n = path.stat().st_size
        if n == 0:
            raise _broken(path, "it is empty")
        check = _CHECKS.get(suffix)
        if check is not None:
            check(path, size, frames)
    except OSError as exc:
        raise os_error(exc, "cannot read back", path) from None


def _broken(path: Path, why: str) -> BrainPainterError:
    try:
        st = os.statvfs(path.parent)
        full = st.f_bavail * st.f_frsize < 1024 * 1024
    except (OSError, AttributeError):
        full = False
    if full:
        return BrainPainterError(f"writing {path.name!r} failed: the disk is full ({why}); nothing was "
                                 "published. Free some space or choose another place.")
    return BrainPainterError(f"writing {path.name!r} failed: {why}; nothing was published (is the disk "
                             "full?). Run again.")


def _check_png(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    data = path.read_bytes()
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        raise _broken(path, "no PNG signature")
    pos, seen_end, dims = 8, False, None
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        crc = data[pos + 8 + length:pos + 12 + length]
        if len(body) != length or len(crc) != 4 or zlib.crc32(kind + body) != struct.unpack(">I", crc)[0]:
            raise _broken(path, f"PNG chunk {kind!r} is truncated or damaged")
        if kind == b"IHDR":
            dims = struct.unpack(">II", body[:8])
        pos += 12 + length
        if kind == b"IEND":
            seen_end = True
            break
    if not seen_end or pos != len(data):
        raise _broken(path, "the PNG is truncated")
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the PNG is {dims}, not {tuple(size)} pixels")


def gif_info(path: Path) -> tuple[tuple[int, int], int]:
    """``((width, height), n_frames)`` of a GIF, walking its blocks (no decoding).

    Raises
    ------
    ValueError
        The file is not a complete GIF.
    """
    with path.open("rb") as fh:
        head = fh.read(13)
        if len(head) != 13 or head[:6] not in (b"GIF87a", b"GIF89a"):
            raise ValueError("no GIF signature")
        w, h, flags = struct.unpack("<HHB", head[6:11])
        if flags & 0x80:
            fh.seek(3 * 2 ** ((flags & 7) + 1), 1)
        n = 0

        def skip_sub_blocks() -> None:
            while True:
                b = fh.read(1)
                if not b:
                    raise ValueError("truncated data")
                if b[0] == 0:
                    return
                chunk = fh.read(b[0])
                if len(chunk) != b[0]:
                    raise ValueError("truncated data")

        while True:
            b = fh.read(1)
            if not b:
                raise ValueError("no trailer (truncated)")
            if b == b";":
                if fh.read(1):
                    raise ValueError("data after the trailer")
                return (w, h), n
            if b == b"!":
                if not fh.read(1):
                    raise ValueError("truncated extension")
                skip_sub_blocks()
            elif b == b",":
                desc = fh.read(9)
                if len(desc) != 9:
                    raise ValueError("truncated image descriptor")
                if desc[8] & 0x80:
                    fh.seek(3 * 2 ** ((desc[8] & 7) + 1), 1)
                if not fh.read(1):
                    raise ValueError("truncated image")
                skip_sub_blocks()
                n += 1
            else:
                raise ValueError(f"unexpected block {b!r}")


def _check_gif(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        dims, n = gif_info(path)
    except ValueError as exc:
        raise _broken(path, f"the GIF is damaged ({exc})") from None
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the GIF is {dims}, not {tuple(size)} pixels")
    if frames is not None and n != frames:
        raise _broken(path, f"the GIF has {n} frames, not {frames}")


_MP4_CONTAINERS = {b"moov", b"trak", b"mdia", b"minf", b"stbl"}


def mp4_boxes(path: Path) -> dict[str, Any]:
    """Top-level box types of an MP4 and the video sample count (``stsz``), walking box headers.

    Returns
    -------
    dict
        ``{"boxes": [type, ...], "samples": [count per track]}``.

    Raises
    ------
    ValueError
        Box sizes do not add up to the file size (a truncated file).
    """
    total = path.stat().st_size
    top: list[str] = []
    samples: list[int] = []
    with path.open("rb") as fh:
        def walk(start: int, end: int, depth: int) -> None:
            pos = start
            while pos < end:
                fh.seek(pos)
                head = fh.read(8)
                if len(head) < 8:
                    raise ValueError("truncated box header")
                size, kind = struct.unpack(">I4s", head)
                header = 8
                if size == 1:
                    ext = fh.read(8)
                    if len(ext) < 8:
                        raise ValueError("truncated box header")
                    size, header = struct.unpack(">Q", ext)[0], 16
                elif size == 0:
                    size = end - pos
                if size < header or pos + size > end:
                    raise ValueError(f"box {kind!r} runs past the end of the file")
                if depth == 0:
                    top.append(kind.decode("latin-1"))
                if kind in _MP4_CONTAINERS and depth < 6:
                    walk(pos + header, pos + size, depth + 1)
                elif kind == b"stsz":
                    body = fh.read(12)
                    if len(body) == 12:
                        samples.append(struct.unpack(">I", body[8:12])[0])
                pos += size

        walk(0, total, 0)
    return {"boxes": top, "samples": samples}


def _check_mp4(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        info = mp4_boxes(path)
    except ValueError as exc:
        raise _broken(path, f"the MP4 is damaged ({exc})") from None
    missing = [b for b in ("ftyp", "moov", "mdat") if b not in info["boxes"]]
    if missing:
        raise _broken(path, f"the MP4 has no {missing[0]!r} box")
    if frames is not None and frames not in info["samples"]:
        raise _broken(path, f"the MP4 has {info['samples']} frames, not {frames}")


def _check_pil(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    from PIL import Image

    try:
        with Image.open(path) as im:
            im.load()
            dims = im.size
    except Exception as exc:  # PIL raises many kinds on damaged files
        raise _broken(path, f"it cannot be decoded ({type(exc).__name__})") from None
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the image is {dims}, not {tuple(size)} pixels")


def _check_pdf(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    with path.open("rb") as fh:
        head = fh.read(5)
        fh.seek(max(0, path.stat().st_size - 1024))
        tail = fh.read()
    if head != b"%PDF-" or b"%%EOF" not in tail:
        raise _broken(path, "the PDF is truncated")


def _check_svg(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise _broken(path, f"the SVG is not complete XML ({exc})") from None
    if not root.tag.endswith("svg"):
        raise _broken(path, "it is not an SVG")


def _check_json(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise _broken(path, f"it is not valid JSON ({exc})") from None


_CHECKS: dict[str, Callable[[Path, tuple[int, int] | None, int | None], None]] = {
    ".png": _check_png, ".gif": _check_gif, ".mp4": _check_mp4, ".tif": _check_pil, ".tiff": _check_pil,
    ".pdf": _check_pdf, ".svg": _check_svg, ".json": _check_json,
}


def json_bytes(obj: object) -> bytes:
    """`obj` as indented JSON; NaN and infinity are refused, so the file is always valid JSON."""
    try:
        return (json.dumps(obj, indent=2, allow_nan=False) + "\n").encode()
    except ValueError as exc:
        raise BrainPainterError(f"the manifest holds a value that is not a finite number ({exc}); "
                                "check the options given.") from None


# -- transactions ------------------------------------------------------------------------------
class _Staged:
    """What every output transaction does on the way out: drop the stage, release the lock,
    and after a failure remove the output folders it created (left empty)."""

    stage: Path | None
    committed: bool
    _lock: Any
    _created: Any

    def __exit__(self, *exc: object) -> None:
        try:
            if self.stage is not None:
                shutil.rmtree(self.stage, ignore_errors=True)
        finally:
            self._lock.__exit__(None, None, None)
            if not self.committed:
                remove_empty(self._created)  # a failed run leaves no empty output folder behind


class FolderTransaction(_Staged):
    """Write several files and a manifest into an output folder, all or nothing.

    Usage::

        with FolderTransaction(out) as tx:
            for name, image in ...:
                write_png(tx.path(name), image)
                tx.expect(name, size=(w, h))
            tx.commit(manifest)

    Leaving the block without :meth:`commit` (an error, Ctrl-C) publishes
    nothing and leaves the folder as it was (apart from creating it).
    """

    def __init__(self, out: str | os.PathLike, what: str = "output folder",
                 manifest: str = MANIFEST) -> None:
        self.out = Path(out)
        self.what = what
        self.manifest = manifest
        self._expected: dict[str, tuple[tuple[int, int] | None, int | None]] = {}
        self._lock: Any = None
        self.stage: Path | None = None
        self.committed = False

    def __enter__(self) -> FolderTransaction:
        self._created: list[Path] = []
        self.out = make_folder(self.out, self.what, self._created)
        try:
            self._lock = folder_lock(self.out, self.what)
            self._lock.__enter__()
        except BaseException:
            remove_empty(self._created)
            raise
        try:
            remove_stale_stages(self.out)
            self.stage = _new_stage(self.out, f"{self.what} {str(self.out)!r}")
        except BaseException:
            self._lock.__exit__(None, None, None)
            remove_empty(self._created)
            raise
        return self

    def path(self, name: str) -> Path:
        """Where to write the file `name` (inside the staging folder)."""
        assert self.stage is not None, "use the transaction as a context manager"
        if Path(name).name != name or name in ("", ".", "..", self.manifest):
            raise ValueError(f"not a plain file name: {name!r}")
        return self.stage / name

    def expect(self, name: str, size: tuple[int, int] | None = None, frames: int | None = None) -> None:
        """Record that `name` is part of the output, with its expected pixel size and frames."""
        self._expected[name] = (size, frames)

    def commit(self, manifest: object | None = None) -> list[Path]:
        """Verify every expected file, then publish them and the manifest (last); returns the paths."""
        assert self.stage is not None
        for name, (size, frames) in self._expected.items():
            staged = self.stage / name
            if not staged.is_file():
                raise BrainPainterError(f"writing {name!r} failed: the file was not made; nothing was "
                                        "published. Run again.")
            verify_file(staged, size, frames)
        data = json_bytes(manifest) if manifest is not None else None
        published = []
        try:
            if data is not None:
                staged_manifest = self.stage / self.manifest
                staged_manifest.write_bytes(data)
                _default_mode(staged_manifest)
            old = self.out / self.manifest
            if old.is_file() or old.is_symlink():
                old.unlink()  # never leave a manifest describing files about to be replaced
                _fsync_dir(self.out)
            for name in self._expected:
                staged = self.stage / name
                _default_mode(staged)
                os.replace(staged, self.out / name)
                published.append(self.out / name)
            if data is not None:
                _fsync_dir(self.out)
                os.replace(self.stage / self.manifest, self.out / self.manifest)
            _fsync_dir(self.out)
        except OSError as exc:
            raise os_error(exc, f"cannot publish into {self.what}", self.out) from None
        self.committed = True
        return published


class FileTransaction(_Staged):
    """Write one output file (figure, movie) through a staging file; publish it if it verifies.

    Usage::

        with FileTransaction(path) as tx:
            save(tx.tmp)
            tx.commit(size=(w, h), frames=n)
    """

    def __init__(self, path: str | os.PathLike, what: str = "--out") -> None:
        self.target = Path(path)
        self.what = what
        self._lock: Any = None
        self.stage: Path | None = None
        self.tmp: Path = self.target

    def __enter__(self) -> FileTransaction:
        self._created: list[Path] = []
        self.committed = False
        folder = make_folder(self.target.parent, "output folder", self._created)
        try:
            self._lock = folder_lock(folder, "output folder")
            self._lock.__enter__()
        except BaseException:
            remove_empty(self._created)
            raise
        try:
            remove_stale_stages(folder)
            self.stage = _new_stage(folder, f"output folder {str(folder)!r}")
            self.tmp = self.stage / ("output" + self.target.suffix.lower())
        except BaseException:
            self._lock.__exit__(None, None, None)
            remove_empty(self._created)
            raise
        return self

    def commit(self, size: tuple[int, int] | None = None, frames: int | None = None) -> Path:
        """Verify the staged file and rename it to the target."""
        if not self.tmp.is_file():
            raise BrainPainterError(f"writing {str(self.target)!r} failed: the encoder wrote nothing; "
                                    "nothing was published.")
        verify_file(self.tmp, size, frames)
        try:
            _default_mode(self.tmp)
            os.replace(self.tmp, self.target)
            _fsync_dir(self.target.parent)
        except OSError as exc:
            raise os_error(exc, "cannot write", self.target) from None
        self.committed = True
        return self.target


# -- whole folders (templates, atlases) -------------------------------------------------------------
def check_replaceable(target: Path, is_ours: Callable[[Path], bool], what: str, hint: str) -> None:
    """Refuse to replace `target` unless it is missing, an empty folder, or made by this program.

    Parameters
    ----------
    target : Path
    is_ours : callable
        True when the folder is one this program made (e.g. its manifest says so).
    what : str
        ``"template folder"``, for messages.
    hint : str
        What to do instead.
    """
    try:
        _check_replaceable(target, is_ours, what, hint)
    except OSError as exc:
        raise os_error(exc, f"cannot use {what}", target) from None


def _check_replaceable(target: Path, is_ours: Callable[[Path], bool], what: str, hint: str) -> None:
    if str(target) in ("", "."):
        raise BrainPainterError(f"{what} must be a new folder's name; {str(target)!r} (the current folder) "
                                f"was given. {hint}")
    if target.is_symlink():
        raise BrainPainterError(f"{what} {str(target)!r} is a symbolic link; give a real folder. {hint}")
    if not target.exists():
        return
    if not target.is_dir():
        raise BrainPainterError(f"{what} {str(target)!r} exists and is not a folder. {hint}")
    here = Path.cwd().resolve()
    real = target.resolve()
    if real == here or real in here.parents:
        raise BrainPainterError(f"{what} {str(target)!r} is the current folder or holds it; it would be "
                                f"replaced. {hint}")
    try:
        empty = not any(target.iterdir())
    except OSError as exc:
        raise os_error(exc, f"cannot read {what}", target) from None
    if not empty and not is_ours(target):
        raise BrainPainterError(f"{what} {str(target)!r} exists, is not empty and was not made by "
                                f"brainpainter; it is left untouched. {hint}")


@contextmanager
def replace_folder(target: str | os.PathLike, is_ours: Callable[[Path], bool], what: str,
                   hint: str) -> Iterator[Path]:
    """Yield a staging folder beside `target`; on success it atomically takes `target`'s place.

    `target` is checked with :func:`check_replaceable` before and again when
    publishing; the parent folder is locked for the whole block.
    """
    target = Path(target).expanduser()
    check_replaceable(target, is_ours, what, hint)
    target = target.absolute()
    parent = make_folder(target.parent, f"parent folder of the {what}")
    with folder_lock(parent, f"folder {str(parent)!r}"):
        remove_stale_stages(parent)
        stage = _new_stage(parent, f"folder {str(parent)!r}")
        try:
            yield stage
            check_replaceable(target, is_ours, what, hint)
            try:
                os.chmod(stage, 0o755)
                if target.exists():
                    old = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX + "old-", dir=parent))
                    os.rename(target, old / "old")  # the old content goes at once...
                    try:
                        os.rename(stage, target)    # ...and the new one takes its place
                    except OSError:
                        os.rename(old / "old", target)  # put the old one back
                        raise
                    shutil.rmtree(old, ignore_errors=True)
                else:
                    os.rename(stage, target)
                _fsync_dir(parent)
            except OSError as exc:
                raise os_error(exc, f"cannot write {what}", target) from None
        finally:
            if stage.exists():
                shutil.rmtree(stage, ignore_errors=True)
