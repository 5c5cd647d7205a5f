"""The plugin registries' entry points of the installed distributions, cached per environment.

Asking :mod:`importlib.metadata` for an entry-point group reads the metadata of every installed
distribution (tens of milliseconds for each of the registries' three groups, 0.07-0.1 s of a cold
``brainpainter render``). The answer changes only when distributions are installed, upgraded or
removed, so it is kept in the user's cache (:mod:`brainpainter.io.user_cache`) under a key made
of ``sys.path`` and, per folder on it, the names and modification times of its ``*.dist-info`` and
``*.egg-info`` folders and of their ``entry_points.txt`` (pip writes a new folder for every
install; editing an ``entry_points.txt`` changes its time): a few hundred ``stat`` calls, about a
millisecond. Any change of the environment, or a corrupt cache file, reads as a miss and the groups
are read again from :mod:`importlib.metadata`.
"""

from __future__ import annotations

import hashlib
import os
import sys

from brainpainter.io import user_cache

#: The cache file (in :func:`brainpainter.io.user_cache.cache_dir`).
CACHE_FILE = "entry-points.json"
#: One entry point: name, ``module:attr`` target, distribution name.
EntryPointRow = tuple[str, str, str]

#: This process's answers, by groups and ``sys.path`` (:func:`forget` empties it).
_memo: dict[tuple[tuple[str, ...], tuple[str, ...]], dict[str, list[EntryPointRow]]] = {}


def environment_key() -> str:
    """A digest of ``sys.path`` and of the distributions' metadata folders on it (names and times)."""
    h = hashlib.sha256()
    for entry in sys.path:
        root = entry or "."
        h.update(b"\0path\0" + root.encode("utf-8", "surrogateescape"))
        try:
            names = sorted(n for n in os.listdir(root) if n.endswith((".dist-info", ".egg-info")))
        except OSError:  # a zip file, a missing folder
            continue
        for name in names:
            folder = os.path.join(root, name)
            parts = [name]
            for path in (folder, os.path.join(folder, "entry_points.txt")):
                try:
                    st = os.stat(path)
                    parts += [str(st.st_mtime_ns), str(st.st_size)]
                except OSError:
                    parts.append("-")
            h.update(("\0".join(parts) + "\n").encode("utf-8", "surrogateescape"))
    return h.hexdigest()


def _read_metadata(groups: tuple[str, ...]) -> dict[str, list[EntryPointRow]]:
    import importlib.metadata as md

    return {g: [(ep.name, ep.value, ep.dist.name if ep.dist is not None else "?")
                for ep in md.entry_points(group=g)] for g in groups}


def _valid(value: object, groups: tuple[str, ...]) -> bool:
    return (isinstance(value, dict) and sorted(value) == sorted(groups)
            and all(isinstance(rows, list) and all(
                isinstance(r, list) and len(r) == 3 and all(isinstance(x, str) for x in r) for r in rows)
                for rows in value.values()))


def entry_points(group: str, groups: tuple[str, ...]) -> list[EntryPointRow]:
    """The entry points of `group`, as :func:`importlib.metadata.entry_points` lists them.

    Parameters
    ----------
    group : str
        One of `groups`.
    groups : tuple of str
        Every group cached together (the registries' groups): one scan of the metadata for all.

    Returns
    -------
    list of (str, str, str)
        ``(name, "module:attr", distribution)`` per entry point, in the order of the scan.
    """
    found = _memo.get((groups, tuple(sys.path)))
    if found is None:
        key = f"{'|'.join(groups)}:{environment_key()}"
        cached = user_cache.read(CACHE_FILE, key)
        if cached is not None and _valid(cached, groups):
            found = {g: [(r[0], r[1], r[2]) for r in rows] for g, rows in cached.items()}
        else:
            found = _read_metadata(groups)
            user_cache.write(CACHE_FILE, key, found)
        _memo[groups, tuple(sys.path)] = found
    return list(found.get(group, []))


def forget() -> None:
    """Look at the installed distributions again on next use (after installing or removing one)."""
    _memo.clear()
