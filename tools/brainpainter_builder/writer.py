"""Write the FreeSurfer licence of a template built from a FreeSurfer subject.

The reproducible ``.npz``/JSON writing and the all-or-nothing output folder
live in the core (:mod:`brainpainter.atlas.writer`, also used for user
atlases); they are re-exported here for the builder's modules.
"""

from __future__ import annotations

import os
from pathlib import Path

from brainpainter.atlas.writer import (
    TEMPLATE_HINT,
    check_out_dir,
    is_template_dir,
    save_npz,
    staged_dir,
    write_json,
)
from brainpainter.errors import BrainPainterError

# The builder's writing API: the licence here, the rest from the core.
__all__ = ["TEMPLATE_HINT", "check_out_dir", "find_license", "is_template_dir", "save_npz", "staged_dir",
           "write_json", "write_license"]


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

