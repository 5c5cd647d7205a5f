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

Folders, locks and OS errors are :mod:`brainpainter.io.folders`; the checks of
written files are :mod:`brainpainter.io.verify`.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.io.folders import (
    STAGE_PREFIX,
    default_mode,
    folder_lock,
    fsync_dir,
    make_folder,
    new_stage,
    os_error,
    remove_empty,
    remove_stale_stages,
)
from brainpainter.io.interrupts import held, mark_published
from brainpainter.io.verify import verify_file

MANIFEST = "manifest.json"


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


def refuse_empty(path: str | os.PathLike[str], what: str) -> str | os.PathLike[str]:
    """`path`, unless it is an empty text (``out=""``), which ``Path`` would turn into the current folder."""
    if isinstance(path, str) and not path.strip():
        raise BrainPainterError(f"{what} is empty ({path!r}), which would mean the current folder; give a "
                                "folder or file name ('.' for the current folder if that is meant).")
    return path


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

    def __init__(self, out: str | os.PathLike[str], what: str = "output folder",
                 manifest: str = MANIFEST) -> None:
        self.out = Path(refuse_empty(out, what))
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
            self.stage = new_stage(self.out, self.what)
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
        published: list[Path] = []
        with held():  # a signal now would leave a half-published folder: it waits for the end
            self._publish(data, published)
        return published

    def _publish(self, data: bytes | None, published: list[Path]) -> None:
        """Rename the staged files (then the manifest) into the output folder; see :meth:`commit`."""
        assert self.stage is not None
        try:
            if data is not None:
                staged_manifest = self.stage / self.manifest
                staged_manifest.write_bytes(data)
                default_mode(staged_manifest)
            old = self.out / self.manifest
            if old.is_file() or old.is_symlink():
                old.unlink()  # never leave a manifest describing files about to be replaced
                fsync_dir(self.out)
            for name in self._expected:
                staged = self.stage / name
                default_mode(staged)
                os.replace(staged, self.out / name)
                published.append(self.out / name)
            if data is not None:
                fsync_dir(self.out)
                os.replace(self.stage / self.manifest, self.out / self.manifest)
            fsync_dir(self.out)
        except OSError as exc:
            raise os_error(exc, f"cannot publish into {self.what}", self.out) from None
        self.committed = True
        mark_published(str(self.out))


class FileTransaction(_Staged):
    """Write one output file (figure, movie) through a staging file; publish it if it verifies.

    Usage::

        with FileTransaction(path) as tx:
            save(tx.tmp)
            tx.commit(size=(w, h), frames=n)
    """

    def __init__(self, path: str | os.PathLike[str], what: str = "--out") -> None:
        self.target = Path(refuse_empty(path, what))
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
            self.stage = new_stage(folder, "output folder")
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
        with held():  # a signal waits until the file is in place (or not)
            try:
                default_mode(self.tmp)
                os.replace(self.tmp, self.target)
                fsync_dir(self.target.parent)
            except OSError as exc:
                raise os_error(exc, "cannot write", self.target) from None
            self.committed = True
            mark_published(str(self.target))
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
def replace_folder(target: str | os.PathLike[str], is_ours: Callable[[Path], bool], what: str,
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
        stage = new_stage(parent, "folder")
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
                fsync_dir(parent)
            except OSError as exc:
                raise os_error(exc, f"cannot write {what}", target) from None
        finally:
            if stage.exists():
                shutil.rmtree(stage, ignore_errors=True)
