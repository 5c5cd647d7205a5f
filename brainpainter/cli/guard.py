"""Run a CLI command so that every failure is one line on stderr and nothing leaks.

:func:`run` wraps the click group:

* user errors (:class:`~brainpainter.errors.BrainPainterError`, click usage
  errors) -> ``error: ...`` on one line, exit code 2;
* OS errors (full disk, read-only file system, name too long, closed pipe,
  permission denied) -> one line, exit code 2;
* SIGINT (Ctrl-C) -> ``interrupted``, exit code 130; SIGTERM ->
  ``terminated``, exit code 143; the output transactions clean up on the way
  out (:mod:`brainpainter.io.transaction`);
* anything else is a bug: ``internal error: ...`` on one line, exit code 1
  (``BRAINPAINTER_DEBUG=1`` shows the traceback).

While a command runs, caches and temporary files of the libraries it loads
(matplotlib's font cache, fontconfig, Blender's user folders, ffmpeg's and
Python's temporary files) go to one temporary folder that is removed when the
command ends, so a run writes nothing outside its output folder but
brainpainter's own cache folder (:mod:`brainpainter.io.user_cache`: the
installed plugins, Mesa's compiled shaders; ``BRAINPAINTER_CACHE=off`` for none). The folder
holds a lock (``flock`` on :data:`RUN_LOCK`) while its process lives; a
process killed with ``kill -9`` cannot remove its folder, so every run first
removes the ``brainpainter-run-*`` folders whose lock nobody holds
(:func:`remove_dead_runs`).
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import click

from brainpainter.errors import BrainPainterError
from brainpainter.io.interrupts import defer, held, published

EXIT_USER = 2
EXIT_INTERNAL = 1
EXIT_SIGINT = 130
EXIT_SIGTERM = 143

#: Environment variables pointed into the run's temporary folder (unless the user set them; the user's
#: ``XDG_CACHE_HOME`` says only where brainpainter's own cache goes, :data:`ALWAYS_PRIVATE`).
CACHE_VARIABLES = {
    "MPLCONFIGDIR": "matplotlib",
    "XDG_CACHE_HOME": "cache",
    "BLENDER_USER_CONFIG": "blender/config",
    "BLENDER_USER_SCRIPTS": "blender/scripts",
    "BLENDER_USER_DATAFILES": "blender/datafiles",
    "BLENDER_USER_EXTENSIONS": "blender/extensions",
    "BLENDER_USER_RESOURCES": "blender/resources",
}

#: Variables pointed into the run's temporary folder even where the user set them: ``XDG_CACHE_HOME`` has
#: given brainpainter's cache folder (:func:`_persistent_caches`) before; Blender made ``thumbnails/`` in it,
#: and with ``BRAINPAINTER_CACHE=off`` a run is to write nothing outside its output.
ALWAYS_PRIVATE = frozenset({"XDG_CACHE_HOME"})

RUN_PREFIX = "brainpainter-run-"
#: The lock file of a run's temporary folder, held (``flock``) by the process that made it while it lives.
RUN_LOCK = ".owner.lock"

#: Mesa's shader cache (llvmpipe's compiled shaders: 0.2-0.3 s of every cold first image) goes to
#: brainpainter's own cache folder, which outlives the run (:mod:`brainpainter.io.user_cache`); with
#: caches off (``BRAINPAINTER_CACHE=off``) it is disabled, as it would only be written into the run's
#: temporary folder (whose removal its writer thread once outlived: "Failed to create ...").
SHADER_CACHE = {"MESA_SHADER_CACHE_DIR": "mesa-shaders"}
NO_DISK_CACHE = {"MESA_SHADER_CACHE_DISABLE": "true"}


def _persistent_caches() -> dict[str, str]:
    """The environment that keeps brainpainter's caches (and Mesa's shaders) in the user's cache
    folder while ``XDG_CACHE_HOME`` points into the run's temporary folder; the user's own settings
    stay."""
    from brainpainter.io import user_cache

    folder = user_cache.cache_dir()
    if folder is None:
        return dict(NO_DISK_CACHE)
    out = {user_cache.CACHE_ENV: str(folder)}
    out.update({var: str(folder / sub) for var, sub in SHADER_CACHE.items()})
    return out


class Stopped(BaseException):
    """A signal asked the run to stop; ``with`` blocks clean up on the way out.

    Not a KeyboardInterrupt, so that no library (click included) turns it into
    something else; it is caught only by :func:`run`.
    """

    exit_code = EXIT_SIGINT
    word = "interrupted"


class Interrupted(Stopped):
    """SIGINT (Ctrl-C)."""


class Terminated(Stopped):
    """SIGTERM."""

    exit_code = EXIT_SIGTERM
    word = "terminated"


def _swallows_exceptions(frame: Any) -> bool:
    """True when an exception raised in `frame` would be printed and dropped, not propagated: inside a
    ``__del__`` or a weak-reference callback (the import system's module-lock ``cb``, ``weakref``'s own:
    a ``WeakValueDictionary``'s ``remove``, a ``WeakSet``'s ``_remove``), up the stack."""
    while frame is not None:
        code = frame.f_code
        if code.co_name == "__del__" or (code.co_name == "cb" and "importlib" in code.co_filename) \
                or code.co_filename.endswith(("weakref.py", "_weakrefset.py")):
            return True
        frame = frame.f_back
    return False


def _on_signal(signum: int, frame: Any) -> None:
    if defer(signum):  # a renderer cannot be interrupted just now: raised when it can
        return
    if _swallows_exceptions(frame):  # raised here it would be lost (and print a traceback): again soon
        again = threading.Timer(0.02, os.kill, (os.getpid(), signum))
        again.daemon = True
        again.start()
        return
    # a second Ctrl-C must not cut the clean-up short (kill -9 still stops everything)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise Terminated() if signum == signal.SIGTERM else Interrupted()


def _hold_lock(root: str) -> int:
    """Lock `root`'s :data:`RUN_LOCK` for this process (the file descriptor; the lock goes when it is
    closed or the process dies). Locked under another name, then renamed: a sweep never sees it unlocked."""
    import fcntl

    fd, tmp = tempfile.mkstemp(prefix=".locking-", dir=root)
    fcntl.flock(fd, fcntl.LOCK_EX)
    os.rename(tmp, os.path.join(root, RUN_LOCK))
    return fd


def remove_dead_runs(folder: str | None = None) -> list[str]:
    """Remove the run folders (``brainpainter-run-*`` in `folder`, default the temporary folder) of
    processes that are gone: those whose :data:`RUN_LOCK` can be locked. A folder without the lock file
    (being made, or made by an earlier version) is left alone. Returns the folders removed."""
    import fcntl

    folder = folder or tempfile.gettempdir()
    gone: list[str] = []
    try:
        names = [n for n in os.listdir(folder) if n.startswith(RUN_PREFIX)]
    except OSError:
        return gone
    for name in names:
        root = os.path.join(folder, name)
        try:
            fd = os.open(os.path.join(root, RUN_LOCK), os.O_RDONLY | os.O_NOFOLLOW)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # held: its process lives
            os.close(fd)
            continue
        try:
            if not os.path.islink(root):
                shutil.rmtree(root, ignore_errors=True)
                gone.append(root)
        finally:
            os.close(fd)
    return gone


@contextmanager
def private_temp() -> Iterator[str]:
    """Point caches and temporary files at a fresh folder (locked while this process lives); remove it
    afterwards. The folders of runs killed earlier go first (:func:`remove_dead_runs`)."""
    remove_dead_runs()
    root = tempfile.mkdtemp(prefix=RUN_PREFIX)
    lock = _hold_lock(root)
    persistent = _persistent_caches()  # before XDG_CACHE_HOME points into the run's folder
    saved = {k: os.environ.get(k) for k in (*CACHE_VARIABLES, *persistent, "TMPDIR")}
    saved_tempdir = tempfile.tempdir
    try:
        for var, sub in CACHE_VARIABLES.items():
            if not os.environ.get(var) or var in ALWAYS_PRIVATE:
                os.environ[var] = os.path.join(root, sub)
        for var, value in persistent.items():
            os.environ.setdefault(var, value)
        tmp = os.path.join(root, "tmp")
        os.makedirs(tmp)
        os.environ["TMPDIR"] = tmp
        tempfile.tempdir = tmp
        yield root
    finally:
        with held():  # a signal now is raised once the folder is gone (run() reports it)
            tempfile.tempdir = saved_tempdir
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
            for _ in range(5):  # a library thread (Blender's shader cache) may still be writing there
                shutil.rmtree(root, ignore_errors=True)
                if not os.path.exists(root):
                    break
                time.sleep(0.05)
            os.close(lock)


@contextmanager
def signals_as_exceptions() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` and SIGINT :class:`Interrupted` in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old_term = signal.signal(signal.SIGTERM, _on_signal)
    old_int = signal.signal(signal.SIGINT, _on_signal)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old_term)
        signal.signal(signal.SIGINT, old_int)


def _silence_stdout() -> None:
    """After stdout failed (closed pipe, full device): send the rest to /dev/null, quietly."""
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError, AttributeError):
        pass


def _say(line: str) -> None:
    try:
        click.echo(line, err=True)
    except OSError:  # stderr itself is gone: nothing more can be said
        pass


def _one_line(text: str, limit: int = 500) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


@contextmanager
def warnings_on_stdout() -> Iterator[None]:
    """A Python warning from a library is one ``warning: ...`` line on stdout, never lines on stderr.

    stderr is kept for the one error line; a warning shown there as
    ``file:line: UserWarning: ...`` plus its source line made a bad input's
    error three lines.
    """
    import warnings

    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
             file: Any = None, line: str | None = None) -> None:
        try:
            click.echo(f"warning: {_one_line(str(message), 300)}")
        except OSError:
            pass

    saved = warnings.showwarning
    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = saved


def run(group: click.Group, argv: Sequence[str] | None = None, prog_name: str = "brainpainter") -> int:
    """Run `group` with `argv`; returns the exit code (see the module docstring)."""
    before = len(published())  # outputs of earlier runs in this process (tests, notebooks) do not count
    try:
        return _run(group, argv, prog_name, before)
    except Stopped as exc:  # the signal came while the run's temporary folder was being removed
        return _stopped(exc, before)


def _stopped(exc: Stopped, before: int) -> int:
    done = published()[before:]
    if done:  # the signal came after the output was complete: it is kept, the run succeeded
        _say(f"{exc.word} after the output was published: {done[-1]} is complete")
        return 0
    _say(f"{exc.word}: nothing was published; partial output was removed")
    return exc.exit_code


def _run(group: click.Group, argv: Sequence[str] | None, prog_name: str, before: int) -> int:
    from brainpainter.io import user_cache

    user_cache.hold()  # a failed command writes no cache file either
    code = EXIT_USER
    try:
        code = _run_command(group, argv, prog_name, before)
        return code
    finally:
        user_cache.release(keep=code == 0)


def _run_command(group: click.Group, argv: Sequence[str] | None, prog_name: str, before: int) -> int:
    with signals_as_exceptions(), private_temp(), warnings_on_stdout():
        try:
            group.main(args=list(argv) if argv is not None else None, prog_name=prog_name,
                       standalone_mode=False)
            sys.stdout.flush()
            return 0
        except Stopped as exc:
            return _stopped(exc, before)
        except (KeyboardInterrupt, click.exceptions.Abort):
            _say("interrupted: nothing was published; partial output was removed")
            return EXIT_SIGINT
        except SystemExit:
            if type(sys.stdout).__name__ == "PacifyFlushWrapper":  # click's answer to a closed pipe
                _silence_stdout()
                _say("error: standard output was closed; the output shown may be incomplete.")
                return EXIT_USER
            raise
        except click.exceptions.Exit as exc:
            return exc.exit_code
        except click.ClickException as exc:  # click's own usage errors
            _say(f"error: {_one_line(exc.format_message())}")
            return exc.exit_code
        except BrainPainterError as exc:
            _say(f"error: {_one_line(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)}")
            return exc.exit_code
        except OSError as exc:
            from brainpainter.io.folders import os_error

            if exc.errno in (errno.EPIPE, errno.ENOSPC, errno.EIO) and exc.filename is None:
                _silence_stdout()
                what = "standard output was closed" if exc.errno == errno.EPIPE else (
                    f"cannot write to standard output ({os.strerror(exc.errno)})")
                _say(f"error: {what}; the output shown may be incomplete.")
                return EXIT_USER
            if exc.errno in _USER_ERRNOS:
                _say(f"error: {_one_line(str(os_error(exc, 'cannot use')))}")
                return EXIT_USER
            return _internal(exc)
        except RecursionError as exc:
            return _internal(exc)
        except Exception as exc:  # a bug: one line, no traceback (BRAINPAINTER_DEBUG=1 shows it)
            return _internal(exc)


_USER_ERRNOS = {errno.ENOSPC, errno.EROFS, errno.ENAMETOOLONG, errno.EACCES, errno.EPERM, errno.EDQUOT,
                errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.ELOOP, errno.EIO, errno.EEXIST}


def _internal(exc: BaseException) -> int:
    if os.environ.get("BRAINPAINTER_DEBUG"):
        raise exc
    _say(_one_line(f"internal error: {type(exc).__name__}: {exc} (set BRAINPAINTER_DEBUG=1 for a "
                   "traceback and please report it)"))
    return EXIT_INTERNAL
