"""The data folder's disk: its budget (:class:`DiskBudget`, ``--max-disk-gb``) and whether an error means
that it is full (the routes answer 507 for both)."""

from __future__ import annotations

import errno
import os
import shutil
import sqlite3
import threading
import time
from pathlib import Path

#: Free bytes below which the data folder's disk counts as full (SQLite then says only "disk I/O error").
FULL_BELOW = 1 << 20


def disk_full(exc: BaseException, root: Path | None = None) -> bool:
    """True when `exc` means that the disk (or the user's quota) of the data folder `root` is full.

    ``OSError`` ENOSPC/EDQUOT (or a one-line error that keeps its ``errno``), SQLite's "database or disk
    is full", and SQLite's "disk I/O error" when `root`'s file system has less than :data:`FULL_BELOW`
    bytes free (SQLite reports a failed write of its shared-memory index so).
    """
    if getattr(exc, "errno", None) in (errno.ENOSPC, errno.EDQUOT):
        return True
    if not isinstance(exc, sqlite3.OperationalError):
        return False
    if "full" in str(exc):
        return True
    if "disk I/O error" in str(exc) and root is not None:
        return disk_free(root) < FULL_BELOW
    return False


def disk_free(root: Path) -> int:
    """Bytes free for this user on the file system of `root` (a large number when it cannot be read)."""
    try:
        return shutil.disk_usage(root).free
    except OSError:
        return 1 << 62


class DiskBudget:
    """The bytes the data folder `root` may use (`limit`; 0: no budget), counted as they are written.

    The folder is walked at most every `max_age_s` seconds; what this process writes in between is added
    by :meth:`charge`, under a lock, so that two writers cannot both fit the last bytes.
    """

    def __init__(self, root: Path, limit: int, max_age_s: float = 10.0) -> None:
        self.root, self.limit, self.max_age_s = root, limit, max_age_s
        self._lock = threading.Lock()
        self._usage: tuple[float, int] = (0.0, 0)

    def used(self, max_age_s: float | None = None) -> int:
        """Bytes used by the folder (whole blocks, as ``du`` counts them; walked again when the last walk
        is older than `max_age_s`, default the budget's)."""
        t, used = self._usage
        if time.monotonic() - t < (self.max_age_s if max_age_s is None else max_age_s):
            return used
        used = 0
        for dirpath, _, names in os.walk(self.root):
            for n in names:
                try:
                    used += os.lstat(os.path.join(dirpath, n)).st_blocks * 512
                except OSError:
                    pass
        self._usage = (time.monotonic(), used)
        return used

    def charge(self, nbytes: int) -> str:
        """Count `nbytes` about to be written; the one-line refusal when they do not fit (nothing is
        counted then), else an empty string."""
        if self.limit <= 0:
            return ""
        with self._lock:
            used = self.used()
            if used + nbytes > self.limit:
                return (f"this server's storage budget ({self.limit / 2**30:.3g} GB) is used up; try again "
                        "after older results expire.")
            self._usage = (self._usage[0], used + -(-nbytes // 4096) * 4096)
            return ""
