"""Which Pythons brainpainter renders on: Blender's ``bpy`` exists for one Python per release.

bpy 4.2-5.0 are built for Python 3.11 (with numpy 1.26), bpy 5.1 and later for
Python 3.13 (numpy >= 2.2); ``pyproject.toml`` picks the matching bpy and numpy
with environment markers. On another Python (e.g. 3.12) brainpainter installs
and reads tables, but rendering needs one of these.
"""

from __future__ import annotations

import importlib.util
import sys

from brainpainter.errors import BrainPainterError

#: (major, minor) -> the bpy releases built for it.
BPY_PYTHONS: dict[tuple[int, int], str] = {(3, 11): "bpy 4.2-5.0", (3, 13): "bpy 5.1 and later"}


def supported_pythons() -> str:
    """``"Python 3.11 (bpy 4.2-5.0) or Python 3.13 (bpy 5.1 and later)"``."""
    return " or ".join(f"Python {a}.{b} ({bpy})" for (a, b), bpy in BPY_PYTHONS.items())


def require_bpy() -> None:
    """Raise a one-line error if Blender's ``bpy`` module is not installed (nothing is imported).

    Raises
    ------
    BrainPainterError
        Naming the running Python and the Pythons that have a bpy.
    """
    if importlib.util.find_spec("bpy") is not None:
        return
    here = "{}.{}".format(*sys.version_info[:2])
    if sys.version_info[:2] in BPY_PYTHONS:
        raise BrainPainterError(
            f"the Blender renderer needs Blender's Python module bpy, which is not installed for this "
            f"Python {here}; install it with 'pip install brainpainter' (or 'pip install bpy')."
        )
    raise BrainPainterError(
        f"the Blender renderer needs Blender's Python module bpy, which exists for {supported_pythons()} "
        f"only, not for the Python {here} running now; make a virtual environment with one of those "
        "(e.g. 'python3.13 -m venv .venv') and 'pip install brainpainter' there."
    )
