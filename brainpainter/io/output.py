"""Write images and manifests safely: sanitised names, atomic writes, metadata."""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
import unicodedata
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.io.rawtable import is_emoji_joiner

#: Longest image name (characters) a table may hold; longer file names are shortened (see safe_name).
MAX_IMAGE_NAME = 1000
#: Longest file-name stem (UTF-8 bytes) made from an image name: with the view and ``.png`` it stays far
#: below the 255 bytes of common file systems (143 on eCryptfs). Longer stems are cut and end in a hash.
MAX_STEM_BYTES = 100
#: Names Windows reserves for devices, with any extension (``CON``, ``con.txt``, ``COM1.x``).
RESERVED_NAMES = frozenset({"CON", "PRN", "AUX", "NUL", "CONIN$", "CONOUT$",
                            *(f"COM{i}" for i in range(10)), *(f"LPT{i}" for i in range(10))})
#: Characters kept besides letters, digits, marks and symbols (emoji).
_KEEP = frozenset("._+-")


def _kept(ch: str) -> bool:
    """Whether `ch` may stay in a file name on Linux, macOS and Windows (letters of any script, emoji)."""
    if ch in _KEEP:
        return True
    if ch.isascii():
        return ch.isalnum()
    return unicodedata.category(ch)[0] in "LNM" or unicodedata.category(ch) in ("So", "Sk")


def safe_name(name: str) -> str:
    """A file-name-safe version of an image name: no path parts, letters of any script kept.

    The name is put in Unicode NFC form (macOS stores names decomposed); runs of
    characters that are unsafe in a file name (path separators, ``:*?"<>|``,
    spaces, punctuation, control characters) become one ``_``; letters, digits
    and marks of any script and symbols such as emoji are kept, so ``"患者 1"``
    becomes ``"患者_1"``. A stem longer than ``MAX_STEM_BYTES`` UTF-8 bytes is
    cut at a character boundary and ends in ``-`` and 8 hex digits of the
    name's SHA-256, so two long names that start alike stay distinct.
    A name with nothing safe in it becomes ``"image"``; one that Windows reserves
    (``CON``, ``NUL``, ``COM1``...) gets a final ``_``.
    """
    text = unicodedata.normalize("NFC", str(name))
    parts: list[str] = []
    for i, ch in enumerate(text):
        if _kept(ch) or is_emoji_joiner(text, i):
            parts.append(ch)
        elif not parts or parts[-1] != "_":
            parts.append("_")
    stem = "".join(parts).strip("._") or "image"
    first, dot, rest = stem.partition(".")
    if first.upper() in RESERVED_NAMES:  # "CON" -> "CON_", "nul.txt" -> "nul_.txt": files Windows can hold
        stem = f"{first}_{dot}{rest}"
    if len(stem.encode("utf-8")) <= MAX_STEM_BYTES:
        return stem
    digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:8]
    cut = stem.encode("utf-8")[:MAX_STEM_BYTES - 9].decode("utf-8", "ignore").rstrip("._")
    return f"{cut}-{digest}"


def same_file_phrase(a: str, b: str) -> str:
    """How image names `a` and `b` with the same :func:`file_key` differ, for messages."""
    if unicodedata.normalize("NFC", a) == unicodedata.normalize("NFC", b):
        return f"{a!a} and {b!a} are the same text with accents encoded differently (Unicode forms)"
    return f"{a!r} and {b!r} differ only in case"


def file_key(name: str) -> str:
    """The key under which two file names are the same on a case-insensitive file system (macOS, Windows)."""
    return unicodedata.normalize("NFC", name).casefold()


def prepare_out_dir(out: str | Path) -> Path:
    """Create `out` if needed and check that files can be written there."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise BrainPainterError(
            f"output {str(out)!r} exists and is not a folder; give a folder path with --out."
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=out, prefix=".bp-write-test-"):
            pass
    except OSError as exc:
        raise BrainPainterError(
            f"output folder {str(out)!r} is not writable ({exc.strerror or exc}); choose another --out."
        ) from None
    return out


def set_default_mode(path: Path | str) -> None:
    """Give a file made through a temporary file (mode 0600) the usual mode (0666 less the umask)."""
    mask = os.umask(0o022)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write via a temporary file in the same folder, then rename."""
    from brainpainter.io.folders import os_error

    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    except OSError as exc:
        raise os_error(exc, "cannot write", path) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        set_default_mode(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise os_error(exc, "cannot write", path) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


_encoder: dict[str, Any] = {}


def load_encoder() -> Any:
    """fpng's encoder, ``encode_ndarray(pixels) -> bytes`` (None when missing: Pillow encodes), loaded once.

    The compiled module ``fpng.fpng_ext`` is loaded from its file without running
    ``fpng/__init__.py``, which only wraps it and imports ``lazy_loader``, whose
    ``lazy.load('cv2')`` walks the interpreter stack with ``inspect.stack()``: 0.15 s
    of a cold first image once bpy is loaded, seconds on a worker thread. Where
    that fails (another layout of the package), ``import fpng`` as usual. Call it
    on the caller's thread before PNG worker threads encode (``PngWriter`` does).
    Not imported with this module, whose names ``brainpainter --help`` needs.
    """
    if "fpng" not in _encoder:
        _encoder["fpng"] = _fpng_extension()
    return _encoder["fpng"]


def _fpng_extension() -> Any:
    import importlib.machinery
    import importlib.util

    try:
        spec = importlib.util.find_spec("fpng")  # finds the package without importing it
    except (ImportError, ValueError):
        spec = None
    if spec is None:  # pragma: no cover - fpng is a dependency; Pillow is the fallback
        return None
    if "fpng" not in sys.modules:
        for folder in spec.submodule_search_locations or ():
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = os.path.join(folder, "fpng_ext" + suffix)
                if not os.path.isfile(path):
                    continue
                try:
                    ext_spec = importlib.util.spec_from_file_location("fpng.fpng_ext", path)
                    assert ext_spec is not None and ext_spec.loader is not None
                    module = importlib.util.module_from_spec(ext_spec)
                    ext_spec.loader.exec_module(module)
                    module.init()  # what fpng/__init__.py does once
                    return module
                except Exception:  # pragma: no cover - fall back to the package's own import
                    break
    import fpng

    return fpng.fpng_ext


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    import struct
    import zlib

    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_bytes(image: NDArray[Any], metadata: dict[str, str] | None = None, dpi: float | None = None) -> bytes:
    """Encode an RGBA uint8 image, shape (h, w, 4), as PNG with iTXt text chunks.

    Uses ``fpng`` (about 10x faster than zlib level 6, lossless, files ~20 %
    larger) when it is installed, else Pillow with ``compress_level=1``. The
    text chunks go right after the header, as Pillow writes them; with `dpi`,
    the print resolution too (a ``pHYs`` chunk in pixels per metre, as Pillow
    and matplotlib write it).
    """
    pixels = np.ascontiguousarray(image, dtype=np.uint8)
    fpng = load_encoder()
    if fpng is not None and pixels.ndim == 3 and pixels.shape[2] in (3, 4):
        import struct

        data = fpng.encode_ndarray(pixels)
        per_metre = int(dpi / 0.0254 + 0.5) if dpi is not None else 0
        chunks = (_png_chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)) if dpi is not None
                  else b"") + b"".join(
            _png_chunk(b"iTXt", k.encode("latin-1") + b"\0\0\0\0\0" + str(v).encode("utf-8"))
            for k, v in (metadata or {}).items())
        head = 8 + 25  # signature, IHDR chunk
        png: bytes = data[:head] + chunks + data[head:]
        return png
    import io

    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    info = PngInfo()
    for k, v in (metadata or {}).items():
        info.add_itxt(k, v)
    buf = io.BytesIO()
    extra: dict[str, Any] = {} if dpi is None else {"dpi": (dpi, dpi)}
    Image.fromarray(pixels).save(buf, format="PNG", pnginfo=info, compress_level=1, **extra)
    return buf.getvalue()


def write_png(path: Path, image: NDArray[Any], metadata: dict[str, str] | None = None) -> None:
    atomic_write_bytes(path, png_bytes(image, metadata))


def write_json(path: Path, obj: object) -> None:
    from brainpainter.io.transaction import json_bytes

    atomic_write_bytes(path, json_bytes(obj))


class PngWriter:
    """Encode and write PNGs on a worker thread while the caller renders the next image.

    PNG compression releases the GIL, so on a multi-core machine it overlaps
    with rendering. At most `max_pending` images wait, which bounds memory.
    Leaving the ``with`` block waits for every write and re-raises the first
    error; each file is written atomically, so an error leaves no partial PNG.
    """

    def __init__(self, max_pending: int = 2) -> None:
        load_encoder()  # on this thread, not the worker's
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="brainpainter-png")
        self._pending: deque[Future[None]] = deque()
        self._max = max_pending

    def submit(self, path: Path, image: NDArray[Any], metadata: dict[str, str] | None = None) -> None:
        """Queue `image` (RGBA uint8, shape (h, w, 4)) for writing to `path`."""
        while len(self._pending) >= self._max:
            self._pending.popleft().result()
        self._pending.append(self._pool.submit(write_png, path, image, metadata))

    def wait(self) -> None:
        """Wait until every queued image is written; re-raise the first error."""
        while self._pending:
            self._pending.popleft().result()

    def __enter__(self) -> PngWriter:
        return self

    def __exit__(self, exc_type: object, *rest: object) -> None:
        try:
            while self._pending:
                future = self._pending.popleft()
                if exc_type is not None:
                    future.cancel()
                    continue
                future.result()
        finally:
            self._pool.shutdown(wait=True)
