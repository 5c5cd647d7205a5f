"""Write template files: byte-for-byte reproducible, all or nothing.

``np.savez_compressed`` stamps every zip member with the current time, so two
builds would differ; :func:`save_npz` writes the same ``.npz`` layout (one
``.npy`` member per array, deflate-compressed, no pickle) with a fixed
timestamp instead. :func:`staged_dir` builds into a hidden sibling
directory and renames it into place only when everything succeeded.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from brainpainter.errors import BrainPainterError

_EPOCH = (1980, 1, 1, 0, 0, 0)


def save_npz(path: str | Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Save arrays as a compressed ``.npz`` that is identical for identical arrays.

    Readable with ``np.load(path, allow_pickle=False)``; members are written in
    the order of `arrays`.
    """
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=6) as zf:
        for name, array in arrays.items():
            array = np.ascontiguousarray(array)
            if array.dtype.hasobject:
                raise TypeError(f"array {name!r} has dtype object; templates hold plain arrays")
            buf = io.BytesIO()
            np.lib.format.write_array(buf, array, allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue(), compress_type=zipfile.ZIP_DEFLATED, compresslevel=6)


def _round(obj, digits: int):
    if isinstance(obj, float):
        return round(obj, digits)
    if isinstance(obj, dict):
        return {k: _round(v, digits) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_round(v, digits) for v in obj]
    if isinstance(obj, np.generic):
        return _round(obj.item(), digits)
    return obj


def write_json(path: str | Path, obj: dict, digits: int = 4) -> None:
    """Write JSON (indented, UTF-8, trailing newline, floats rounded to `digits`)."""
    text = json.dumps(_round(obj, digits), indent=2, ensure_ascii=False)
    Path(path).write_text(text + "\n", encoding="utf-8")


def write_license(path: str | Path, license_file: str | Path, subject: str, version: str) -> None:
    """Write ``LICENSE.FreeSurfer.txt``: attribution line, derived-data notice, Part B.

    Parameters
    ----------
    path : path-like
        Output file.
    license_file : path-like
        FreeSurfer's ``LICENSE.FreeSurfer.txt`` (the full agreement).
    subject, version : str
        What the template was made from (``"fsaverage"``, ``"freesurfer-7.3.2"``).
    """
    license_file = Path(license_file)
    try:
        text = license_file.read_text(encoding="utf-8")
    except OSError as exc:
        raise BrainPainterError(f"cannot read the FreeSurfer licence {license_file}: {exc}") from None
    lines = text.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.startswith("PART B"))
        stop = next(i for i, line in enumerate(lines) if line.startswith("PART C"))
    except StopIteration:
        raise BrainPainterError(
            f"{license_file} is not the FreeSurfer Software License Agreement "
            "(no 'PART B' / 'PART C' headings found)") from None
    head = []
    for line in lines:  # the attribution paragraph at the top, up to its blank line
        if not line.strip():
            break
        head.append(line)
    vname = version.removeprefix("freesurfer-")
    notice = [
        "",
        f"The files in this directory are data derived (modified) from FreeSurfer {vname}'s",
        f"{subject} subject (surfaces, cortical parcellations and aseg segmentation),",
        "remeshed and decimated by the brainpainter template builder. They are not",
        "endorsed by MGH. Research use; see the licence below.",
        "",
    ]
    body = [line.rstrip() for line in lines[start:stop]]
    while body and not body[-1].strip():
        body.pop()
    Path(path).write_text("\n".join([*head, *notice, *body]) + "\n", encoding="utf-8")


def find_license(subject_dir: str | Path) -> Path | None:
    """FreeSurfer's licence text near a subject (``../../LICENSE.FreeSurfer.txt`` etc.)."""
    subject_dir = Path(subject_dir).resolve()
    candidates = [subject_dir.parent.parent / "LICENSE.FreeSurfer.txt",
                  subject_dir.parent.parent / "LICENSE.txt"]
    if os.environ.get("FREESURFER_HOME"):
        home = Path(os.environ["FREESURFER_HOME"])
        candidates += [home / "LICENSE.FreeSurfer.txt", home / "LICENSE.txt", home / "license.txt"]
    for c in candidates:
        if c.is_file():
            return c
    return None


TEMPLATE_HINT = ("give a new or empty folder with --out (an existing folder is replaced only when it is a "
                 "template made by brainpainter)")


def is_template_dir(path: Path) -> bool:
    """Whether `path` holds a template made by this program (its manifest says ``brainpainter-template``)."""
    from brainpainter.atlas.template import FORMAT

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
    from brainpainter.io.transaction import check_replaceable

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
    from brainpainter.io.transaction import replace_folder

    with replace_folder(out_dir, is_template_dir, "template folder",
                        f"It is not a template; {TEMPLATE_HINT}.") as stage:
        yield stage
