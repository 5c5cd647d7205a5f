"""Checks that a written output file is what it claims to be, before it is published.

:func:`verify_file` reads the structure of PNG, GIF, MP4, TIFF, PDF, SVG and
JSON files (and their pixel size and frame count where asked) so that a
truncated or corrupt file is never renamed into place.
"""

from __future__ import annotations

import json
import os
import struct
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.io.folders import os_error


def verify_file(path: Path, size: tuple[int, int] | None = None, frames: int | None = None) -> None:
    """Check that `path` is a complete file of its format (by its ending), of `size` and `frames`.

    Parameters
    ----------
    path : Path
        ``.png``, ``.gif``, ``.mp4``, ``.tif``/``.tiff``, ``.pdf``, ``.svg`` or ``.json``.
    size : (width, height), optional
        Expected pixel size (PNG, GIF, TIFF).
    frames : int, optional
        Expected number of frames (GIF, MP4).

    Raises
    ------
    BrainPainterError
        The file is empty, truncated or not what was expected.
    """
    suffix = path.suffix.lower()
    try:
        n = path.stat().st_size
        if n == 0:
            raise _broken(path, "it is empty")
        check = _CHECKS.get(suffix)
        if check is not None:
            check(path, size, frames)
    except OSError as exc:
        raise os_error(exc, "cannot read back", path) from None


def _broken(path: Path, why: str) -> BrainPainterError:
    try:
        st = os.statvfs(path.parent)
        full = st.f_bavail * st.f_frsize < 1024 * 1024
    except (OSError, AttributeError):
        full = False
    if full:
        return BrainPainterError(f"writing {path.name!r} failed: the disk is full ({why}); nothing was "
                                 "published. Free some space or choose another place.")
    return BrainPainterError(f"writing {path.name!r} failed: {why}; nothing was published (is the disk "
                             "full?). Run again.")


def _check_png(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    data = path.read_bytes()
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        raise _broken(path, "no PNG signature")
    pos, seen_end, dims = 8, False, None
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        crc = data[pos + 8 + length:pos + 12 + length]
        if len(body) != length or len(crc) != 4 or zlib.crc32(kind + body) != struct.unpack(">I", crc)[0]:
            raise _broken(path, f"PNG chunk {kind!r} is truncated or damaged")
        if kind == b"IHDR":
            dims = struct.unpack(">II", body[:8])
        pos += 12 + length
        if kind == b"IEND":
            seen_end = True
            break
    if not seen_end or pos != len(data):
        raise _broken(path, "the PNG is truncated")
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the PNG is {dims}, not {tuple(size)} pixels")


def gif_info(path: Path) -> tuple[tuple[int, int], int]:
    """``((width, height), n_frames)`` of a GIF, walking its blocks (no decoding).

    Raises
    ------
    ValueError
        The file is not a complete GIF.
    """
    with path.open("rb") as fh:
        head = fh.read(13)
        if len(head) != 13 or head[:6] not in (b"GIF87a", b"GIF89a"):
            raise ValueError("no GIF signature")
        w, h, flags = struct.unpack("<HHB", head[6:11])
        if flags & 0x80:
            fh.seek(3 * 2 ** ((flags & 7) + 1), 1)
        n = 0

        def skip_sub_blocks() -> None:
            while True:
                b = fh.read(1)
                if not b:
                    raise ValueError("truncated data")
                if b[0] == 0:
                    return
                chunk = fh.read(b[0])
                if len(chunk) != b[0]:
                    raise ValueError("truncated data")

        while True:
            b = fh.read(1)
            if not b:
                raise ValueError("no trailer (truncated)")
            if b == b";":
                if fh.read(1):
                    raise ValueError("data after the trailer")
                return (w, h), n
            if b == b"!":
                if not fh.read(1):
                    raise ValueError("truncated extension")
                skip_sub_blocks()
            elif b == b",":
                desc = fh.read(9)
                if len(desc) != 9:
                    raise ValueError("truncated image descriptor")
                if desc[8] & 0x80:
                    fh.seek(3 * 2 ** ((desc[8] & 7) + 1), 1)
                if not fh.read(1):
                    raise ValueError("truncated image")
                skip_sub_blocks()
                n += 1
            else:
                raise ValueError(f"unexpected block {b!r}")


def _check_gif(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        dims, n = gif_info(path)
    except ValueError as exc:
        raise _broken(path, f"the GIF is damaged ({exc})") from None
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the GIF is {dims}, not {tuple(size)} pixels")
    if frames is not None and n != frames:
        raise _broken(path, f"the GIF has {n} frames, not {frames}")


_MP4_CONTAINERS = {b"moov", b"trak", b"mdia", b"minf", b"stbl"}


def mp4_boxes(path: Path) -> dict[str, Any]:
    """Top-level box types of an MP4 and the video sample count (``stsz``), walking box headers.

    Returns
    -------
    dict
        ``{"boxes": [type, ...], "samples": [count per track]}``.

    Raises
    ------
    ValueError
        Box sizes do not add up to the file size (a truncated file).
    """
    total = path.stat().st_size
    top: list[str] = []
    samples: list[int] = []
    with path.open("rb") as fh:
        def walk(start: int, end: int, depth: int) -> None:
            pos = start
            while pos < end:
                fh.seek(pos)
                head = fh.read(8)
                if len(head) < 8:
                    raise ValueError("truncated box header")
                size, kind = struct.unpack(">I4s", head)
                header = 8
                if size == 1:
                    ext = fh.read(8)
                    if len(ext) < 8:
                        raise ValueError("truncated box header")
                    size, header = struct.unpack(">Q", ext)[0], 16
                elif size == 0:
                    size = end - pos
                if size < header or pos + size > end:
                    raise ValueError(f"box {kind!r} runs past the end of the file")
                if depth == 0:
                    top.append(kind.decode("latin-1"))
                if kind in _MP4_CONTAINERS and depth < 6:
                    walk(pos + header, pos + size, depth + 1)
                elif kind == b"stsz":
                    body = fh.read(12)
                    if len(body) == 12:
                        samples.append(struct.unpack(">I", body[8:12])[0])
                pos += size

        walk(0, total, 0)
    return {"boxes": top, "samples": samples}


def _check_mp4(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        info = mp4_boxes(path)
    except ValueError as exc:
        raise _broken(path, f"the MP4 is damaged ({exc})") from None
    missing = [b for b in ("ftyp", "moov", "mdat") if b not in info["boxes"]]
    if missing:
        raise _broken(path, f"the MP4 has no {missing[0]!r} box")
    if frames is not None and frames not in info["samples"]:
        raise _broken(path, f"the MP4 has {info['samples']} frames, not {frames}")


def _check_pil(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    from PIL import Image

    try:
        with Image.open(path) as im:
            im.load()
            dims = im.size
    except Exception as exc:  # PIL raises many kinds on damaged files
        raise _broken(path, f"it cannot be decoded ({type(exc).__name__})") from None
    if size is not None and dims != tuple(size):
        raise _broken(path, f"the image is {dims}, not {tuple(size)} pixels")


def _check_pdf(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    with path.open("rb") as fh:
        head = fh.read(5)
        fh.seek(max(0, path.stat().st_size - 1024))
        tail = fh.read()
    if head != b"%PDF-" or b"%%EOF" not in tail:
        raise _broken(path, "the PDF is truncated")


def _check_svg(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise _broken(path, f"the SVG is not complete XML ({exc})") from None
    if not root.tag.endswith("svg"):
        raise _broken(path, "it is not an SVG")


def _check_json(path: Path, size: tuple[int, int] | None, frames: int | None) -> None:
    try:
        json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise _broken(path, f"it is not valid JSON ({exc})") from None


_CHECKS: dict[str, Callable[[Path, tuple[int, int] | None, int | None], None]] = {
    ".png": _check_png, ".gif": _check_gif, ".mp4": _check_mp4, ".tif": _check_pil, ".tiff": _check_pil,
    ".pdf": _check_pdf, ".svg": _check_svg, ".json": _check_json,
}
