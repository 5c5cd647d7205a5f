"""The zip of an ``images`` job's files, made while it is downloaded (it is never stored: it would copy
every PNG)."""

from __future__ import annotations

import io
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any


def zip_name(job_id: str) -> str:
    """The name of an ``images`` job's zip of all its files."""
    return f"brainpainter-{job_id[:8]}.zip"


def zip_stream(out: Path, names: list[str], chunk: int = 1 << 20) -> Iterator[bytes]:
    """The bytes of a zip of `names` (files in `out`), made as they are sent: nothing is stored.

    PNGs are compressed already, so members are stored; memory holds about one `chunk`.
    """
    class _Sink(io.RawIOBase):
        def __init__(self) -> None:
            self.parts: list[bytes] = []
            self.pos = 0

        def writable(self) -> bool:
            return True

        def write(self, b: Any) -> int:
            data = bytes(b)
            self.parts.append(data)
            self.pos += len(data)
            return len(data)

        def tell(self) -> int:
            return self.pos

        def take(self) -> bytes:
            data, self.parts = b"".join(self.parts), []
            return data

    sink = _Sink()
    with zipfile.ZipFile(sink, "w", compression=zipfile.ZIP_STORED) as zf:
        for n in names:
            path = out / n
            info = zipfile.ZipInfo.from_file(path, arcname=n)
            with path.open("rb") as src, zf.open(info, "w", force_zip64=True) as dst:
                while block := src.read(chunk):
                    dst.write(block)
                    yield sink.take()
            yield sink.take()
    yield sink.take()
