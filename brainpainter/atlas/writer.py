"""Write template and atlas files: byte-for-byte reproducible, all or nothing.

``np.savez_compressed`` stamps every zip member with the current time, so two
builds would differ; :func:`save_npz` writes the same ``.npz`` layout (one
``.npy`` member per array, deflate-compressed, no pickle) with a fixed
timestamp instead. :func:`staged_dir` builds into a hidden sibling
directory and renames it into place only when everything succeeded.

Used by the core (label-set and volume atlases) and by the template builder
(``tools/brainpainter_builder``), which imports it from here.
"""

from __future__ import annotations

import contextlib
import io
import json
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.template import FORMAT
from brainpainter.io.transaction import check_replaceable, replace_folder

_EPOCH = (1980, 1, 1, 0, 0, 0)
TEMPLATE_HINT = ("give a new or empty folder with --out (an existing folder is replaced only when it is a "
                 "template made by brainpainter)")


def save_npz(path: str | Path, arrays: Mapping[str, NDArray[Any]]) -> None:
    """Save arrays as a compressed ``.npz`` that is identical for identical arrays.

    Readable with ``np.load(path, allow_pickle=False)``; members are written in
    the order of `arrays`.

    Parameters
    ----------
    path : path-like
        The ``.npz`` file to write.
    arrays : mapping of str to ndarray
        Member name (without ``.npy``) to array of any shape and plain dtype.
    """
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=6) as zf:
        for name, array in arrays.items():
            array = np.ascontiguousarray(array)
            if array.dtype.hasobject:
                raise TypeError(f"array {name!r} has dtype object; templates hold plain arrays")
            buf = io.BytesIO()
            np.lib.format.write_array(buf, array, allow_pickle=False)  # type: ignore[no-untyped-call]
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue(), compress_type=zipfile.ZIP_DEFLATED, compresslevel=6)


def _round(obj: Any, digits: int) -> Any:
    if isinstance(obj, float):
        return round(obj, digits)
    if isinstance(obj, dict):
        return {k: _round(v, digits) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_round(v, digits) for v in obj]
    if isinstance(obj, np.generic):
        return _round(obj.item(), digits)
    return obj


def write_json(path: str | Path, obj: dict[str, Any], digits: int = 4) -> None:
    """Write JSON (indented, UTF-8, trailing newline, floats rounded to `digits`)."""
    text = json.dumps(_round(obj, digits), indent=2, ensure_ascii=False)
    Path(path).write_text(text + "\n", encoding="utf-8")


def is_template_dir(path: Path) -> bool:
    """Whether `path` holds a template made by this program (its manifest says ``brainpainter-template``)."""
    manifest = Path(path) / "manifest.json"
    try:
        if not manifest.is_file() or manifest.is_symlink() or manifest.stat().st_size > 64 * 2**20:
            return False
        data = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    return isinstance(data, dict) and data.get("format") == FORMAT


def check_out_dir(out_dir: str | Path) -> None:
    """Refuse an output that is not new, empty or a template made by brainpainter (before building)."""
    check_replaceable(Path(out_dir).expanduser(), is_template_dir, "template folder",
                      f"It is not a template; {TEMPLATE_HINT}.")


@contextlib.contextmanager
def staged_dir(out_dir: str | Path) -> Iterator[Path]:
    """Yield a hidden sibling directory; move it to `out_dir` if the block succeeds.

    An existing `out_dir` is replaced only if it is empty or a template made
    by brainpainter (``manifest.json`` with ``"format": "brainpainter-template"``);
    anything else is refused and left untouched. The parent folder is locked
    while building; on any error the staging directory is deleted, so a failed
    build leaves nothing behind.
    """
    with replace_folder(out_dir, is_template_dir, "template folder",
                        f"It is not a template; {TEMPLATE_HINT}.") as stage:
        yield stage
