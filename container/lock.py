"""Write the container image's lock: brainpainter's runtime dependencies, as installed here, pinned.

Run with the Python (3.11 or 3.13) of an environment where brainpainter is installed and its tests pass::

    python container/lock.py > container/requirements-py311.txt

Only the dependencies of ``brainpainter`` itself are followed (no extras: no test, builder or cluster
packages), with environment markers evaluated for this interpreter. The image installs exactly these
versions (``pip install -r``), so a rebuild gives the same packages.
"""

from __future__ import annotations

import sys
from importlib import metadata

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = "brainpainter"


def pinned_closure(root: str) -> dict[str, str]:
    """Return ``{distribution name: installed version}`` for every runtime dependency of ``root``."""
    pins: dict[str, str] = {}
    visited: set[tuple[str, frozenset[str]]] = set()
    todo: list[tuple[str, frozenset[str]]] = [(root, frozenset())]
    while todo:
        name, extras = todo.pop()
        key = canonicalize_name(name)
        if (key, extras) in visited:
            continue
        visited.add((key, extras))
        dist = metadata.distribution(name)
        if key != canonicalize_name(root):
            pins[dist.metadata["Name"]] = dist.version
        environments = [{"extra": extra} for extra in sorted(extras)] or [{"extra": ""}]
        for text in dist.requires or []:
            req = Requirement(text)
            if req.marker is not None and not any(req.marker.evaluate(env) for env in environments):
                continue
            todo.append((req.name, frozenset(req.extras)))
    return pins


def main() -> None:
    pins = pinned_closure(ROOT)
    version = f"{sys.version_info[0]}.{sys.version_info[1]}"
    print(f"# brainpainter's runtime dependencies for Python {version}, pinned as installed where the tests "
          "pass.\n# Made by container/lock.py; the Containerfile installs exactly these (pip install -r).")
    for name in sorted(pins, key=str.lower):
        print(f"{name}=={pins[name]}")


if __name__ == "__main__":
    main()
