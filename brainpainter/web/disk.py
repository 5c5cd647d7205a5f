"""Whether an error means that the server's disk is full (the routes answer 507 for it)."""

from __future__ import annotations

import errno
import shutil
import sqlite3
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
