"""Fake installed distributions: what pip leaves in site-packages, for testing plugin discovery.

``fake_distribution`` writes a minimal installed distribution (a package plus
its ``.dist-info`` with ``entry_points.txt``) into a folder; put that folder
on ``sys.path`` with :func:`installed` to make the registries see it.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path


def fake_distribution(
    root: Path,
    name: str,
    entry_points: Mapping[str, Mapping[str, str]],
    files: Mapping[str, str],
    version: str = "0.1.0",
) -> Path:
    """Write an installed distribution into `root`.

    Parameters
    ----------
    root : Path
        Folder that will go on ``sys.path`` (like site-packages).
    name : str
        Distribution name.
    entry_points : mapping
        ``{group: {entry name: "module:attr"}}``.
    files : mapping
        ``{relative path: text}`` of the package's files.
    """
    root.mkdir(parents=True, exist_ok=True)
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    dist = root / f"{name.replace('-', '_')}-{version}.dist-info"
    dist.mkdir(exist_ok=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    lines = []
    for group, entries in entry_points.items():
        lines.append(f"[{group}]")
        lines.extend(f"{k} = {v}" for k, v in entries.items())
        lines.append("")
    (dist / "entry_points.txt").write_text("\n".join(lines))
    return root


@contextmanager
def installed(root: Path) -> Iterator[None]:
    """Put `root` on ``sys.path`` and refresh the registries for the duration."""
    from brainpainter.atlas import registry
    sys.path.insert(0, str(root))
    registry.reset_all()
    try:
        yield
    finally:
        sys.path.remove(str(root))
        for mod in [m for m, v in sys.modules.items() if str(root) in str(getattr(v, "__file__", "") or "")]:
            del sys.modules[mod]
        registry.reset_all()


def pip_install(src: Path, target: Path, scratch: Path) -> Path:
    """Install the distribution in folder `src` into `target` with pip (no index, no dependencies).

    `src` is copied to `scratch` first (without build leftovers), so the
    source tree is left as it was. Returns `target`, for :func:`installed`.
    """
    import shutil
    import subprocess

    copy = Path(scratch) / Path(src).name
    shutil.copytree(src, copy, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--no-index", "--target", str(target), str(copy)],
        check=True, capture_output=True,
    )
    return Path(target)
