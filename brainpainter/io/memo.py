"""Results kept in this process, for work that gives the same arrays every time it is asked.

A figure of a map reads the same template meshes, builds the same edge tables and vertex orders
and samples a volume at the same voxel positions as the figure before it: only the map's values
change. :class:`Memo` keeps such results in memory, most recently used first, up to a number of
bytes, under a key that says exactly what they were computed from: a file's path and
``os.stat`` (size, modification time, inode), or the SHA-256 of the arrays themselves
(:func:`array_key`; about 5 ms for a hemisphere's vertices and triangles). Kept arrays are made
read-only, so a caller that would change one in place fails at once instead of changing the next
caller's result. Safe to use from several threads (two may compute the same value once each).
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")


def array_key(*arrays: Any) -> bytes:
    """SHA-256 of arrays' dtypes, shapes and bytes: equal keys, equal arrays.

    Parameters
    ----------
    *arrays : array-like
    """
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.data.cast("B"))
    return h.digest()


def file_key(path: str | os.PathLike[str]) -> tuple[str, int, int, int]:
    """A file's resolved path, size, modification time (ns) and inode: a new key when it is rewritten."""
    resolved = Path(path).resolve()
    st = resolved.stat()
    return str(resolved), st.st_size, st.st_mtime_ns, st.st_ino


def _arrays(value: Any) -> list[np.ndarray[Any, Any]]:
    """The ndarrays in `value`: itself, or inside tuples, lists, dicts and dataclasses."""
    if isinstance(value, np.ndarray):
        return [value]
    if isinstance(value, (tuple, list)):
        return [a for v in value for a in _arrays(v)]
    if isinstance(value, dict):
        return [a for v in value.values() for a in _arrays(v)]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [a for f in dataclasses.fields(value) for a in _arrays(getattr(value, f.name))]
    return []


class Memo:
    """Values kept by key, most recently used first, while their arrays take at most `max_bytes`.

    Parameters
    ----------
    max_bytes : int
        The newest value is always kept, however large; older ones go first.
    """

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = int(max_bytes)
        self._items: OrderedDict[Hashable, tuple[Any, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, key: Hashable, compute: Callable[[], T]) -> T:
        """The value kept under `key`, or ``compute()`` kept (its arrays made read-only) and returned."""
        with self._lock:
            item = self._items.get(key)
            if item is not None:
                self._items.move_to_end(key)
                kept: T = item[0]
                return kept
        value = compute()
        arrays = _arrays(value)
        for a in arrays:
            a.flags.writeable = False
        size = sum(a.nbytes for a in arrays)
        with self._lock:
            if key not in self._items:
                self._items[key] = (value, size)
                self._bytes += size
            while self._bytes > self.max_bytes and len(self._items) > 1:
                _, (_, dropped) = self._items.popitem(last=False)
                self._bytes -= dropped
        return value

    def clear(self) -> None:
        """Forget every value."""
        with self._lock:
            self._items.clear()
            self._bytes = 0

    def __len__(self) -> int:
        return len(self._items)

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays kept."""
        return self._bytes
