"""The stored form of a file upload (a map pair, a volume, tractograms): one blob in the store.

A bundle is its kind's magic line, one line of JSON (the header: the upload's report and a
``files`` list of ``{tag: ..., "name": ..., "size": ...}``), then the files' bytes one after the
other. :mod:`brainpainter.web.maps` tags each file with its hemisphere (``hemi``),
:mod:`brainpainter.web.tracts` with its role (``role``: ``bundles`` or ``values``).

The header has no size limit of its own: whatever the server accepted (a report listing thousands of
images, a volume's per-image means) must read back. Its files are what the upload's reader read (arrays,
kept streamlines), so a bundle stays within the server's limits on images and streamlines, however much
the upload inflated to.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError


def write_bundle(target: Path, magic: bytes, header: dict[str, Any], tag: str,
                 files: list[tuple[str | None, Path]]) -> None:
    """Write `header` (with its ``files`` list added last) and `files`, ``(tag value, path)``, to `target`."""
    header = {**header, "files": [{tag: t, "name": p.name, "size": p.stat().st_size} for t, p in files]}
    with target.open("wb") as fh:
        fh.write(magic + json.dumps(header).encode() + b"\n")
        for _, p in files:
            with p.open("rb") as src:
                shutil.copyfileobj(src, fh)


def bundle_header(data: bytes, magic: bytes, tag: str, allowed: tuple[str, ...],
                  damaged: str) -> tuple[dict[str, Any], int]:
    """The JSON header of bundle `data` and where its files start.

    Raises
    ------
    BrainPainterError
        `damaged` (one line) when the header is unreadable, a file's `tag` is not `allowed`, or the
        sizes do not add up to the data.
    """
    end = data.find(b"\n", len(magic)) if data.startswith(magic) else -1
    try:
        if end < 0:
            raise ValueError("no header")
        header = json.loads(data[len(magic):end])
        files = header["files"]
        if sum(int(f["size"]) for f in files) != len(data) - end - 1 or not all(
                f[tag] in allowed for f in files):
            raise ValueError("sizes")
    except (ValueError, KeyError, TypeError):
        raise BrainPainterError(damaged) from None
    return header, end + 1


def members(data: bytes, header: dict[str, Any], start: int) -> Iterator[tuple[dict[str, Any], bytes]]:
    """Each file of a bundle: its header entry and its bytes (`start` from :func:`bundle_header`)."""
    for f in header["files"]:
        size = int(f["size"])
        yield f, data[start:start + size]
        start += size


def written_once(data: bytes, root: Path, kind: str, fill: Callable[[Path], None]) -> Path:
    """The folder ``root/incoming/<kind>-<sha256>`` of bundle `data`'s files, written once by `fill` (into
    a new folder renamed into place: a folder present is complete; two uploads never share one).

    Its time is renewed on every use: the store deletes folders of ``incoming`` unused for an hour (a
    later use writes them again).
    """
    folder = root / "incoming" / f"{kind}-{hashlib.sha256(data).hexdigest()[:32]}"
    if not folder.is_dir():
        (root / "incoming").mkdir(mode=0o700, parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix=f".{kind}-", dir=root / "incoming"))
        fill(work)
        try:
            os.rename(work, folder)
        except OSError:  # another process wrote it first: the same content
            shutil.rmtree(work, ignore_errors=True)
    with contextlib.suppress(OSError):
        os.utime(folder)
    return folder
