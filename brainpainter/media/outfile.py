"""Checking an output file before anything is rendered: its ending, its folder, write permission."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from brainpainter.errors import BrainPainterError


def check_out_file(out: str | Path, suffixes: Iterable[str], what: str = "--out") -> Path:
    """Check that a file can be written at `out` without creating anything.

    Parameters
    ----------
    out : path-like
    suffixes : iterable of str
        Allowed file-name endings, e.g. ``(".png", ".pdf")``.
    what : str
        The option name used in messages.

    Returns
    -------
    Path

    Raises
    ------
    BrainPainterError
        Wrong ending, an existing folder of that name, or a folder that does not
        exist and cannot be created, or cannot be written to.
    """
    path = Path(out)
    suffixes = tuple(suffixes)
    if path.suffix.lower() not in suffixes:
        raise BrainPainterError(
            f"{what} must be a file name ending in {', '.join(suffixes)}; {str(out)!r} was given."
        )
    if path.is_dir():
        raise BrainPainterError(f"{what} {str(out)!r} is a folder; give a file name such as "
                                f"{str(path / ('figure' + suffixes[0]))!r}.")
    parent = path.parent
    ancestor = parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise BrainPainterError(
            f"{what} {str(out)!r} cannot be written: {str(ancestor)!r} is a file, not a folder; "
            "choose another path."
        )
    if parent.exists():
        import tempfile

        try:
            with tempfile.NamedTemporaryFile(dir=parent, prefix=".bp-write-test-"):
                pass
        except OSError as exc:
            raise BrainPainterError(
                f"{what} {str(out)!r} cannot be written: folder {str(parent)!r} is not writable "
                f"({exc.strerror or exc}); choose another path."
            ) from None
    elif not os.access(ancestor, os.W_OK | os.X_OK):
        raise BrainPainterError(
            f"{what} {str(out)!r} cannot be written: folder {str(ancestor)!r} is not writable; "
            "choose another path."
        )
    return path
