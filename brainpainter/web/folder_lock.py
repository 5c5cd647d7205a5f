"""One server per data folder: ``DATA_DIR/server.lock``, held (``flock``) for the life of the process."""

from __future__ import annotations

from pathlib import Path
from typing import Any

_HELD_LOCKS: dict[str, Any] = {}


def lock_data_dir(data_dir: str | Path) -> None:
    """Hold ``DATA_DIR/server.lock`` for the life of this process: one server per data folder.

    A second server on the same folder would re-queue the first one's running jobs. The lock
    (``flock``) goes with the process, even on ``kill -9``; calling again in the same process is a no-op.

    Raises
    ------
    BrainPainterError
        Another process holds the folder.
    """
    import fcntl

    from brainpainter.errors import BrainPainterError

    root = Path(data_dir).resolve()
    if str(root) in _HELD_LOCKS:
        return
    root.mkdir(parents=True, exist_ok=True)
    fh = open(root / "server.lock", "a+")  # held open (and locked) for the life of the process
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        fh.close()
        raise BrainPainterError(
            f"another brainpainter serve is using --data-dir {str(root)!r}; stop it, or give this server "
            "its own --data-dir."
        ) from None
    _HELD_LOCKS[str(root)] = fh


def unlock_data_dir(data_dir: str | Path) -> None:
    """Let go of the folder locked by :func:`lock_data_dir` in this process (no-op when not held)."""
    fh = _HELD_LOCKS.pop(str(Path(data_dir).resolve()), None)
    if fh is not None:
        fh.close()  # closing the file releases the flock
