"""Import pymeshlab so that Blender's ``bpy`` can still be imported afterwards.

pymeshlab and bpy both ship a ``libembree4.so.4``; pymeshlab's is older. If
pymeshlab loads first, the dynamic loader reuses its copy for bpy, and
``import bpy`` fails with ``undefined symbol: rtcGetSceneTraversable``. Loading
bpy's newer copy first (by path, globally) lets both work in one process, so a
notebook or test session can build a template and then render it.
"""

from __future__ import annotations

import ctypes
import importlib.util
from pathlib import Path
from types import ModuleType


def _preload_bpy_embree() -> None:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        return
    for folder in spec.submodule_search_locations:
        for lib in sorted(Path(folder, "lib").glob("libembree4.so*")):
            try:
                ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
                return
            except OSError:
                continue


def import_pymeshlab() -> ModuleType:
    """Return the pymeshlab module, loaded in a bpy-compatible way."""
    _preload_bpy_embree()
    import pymeshlab

    return pymeshlab
