"""A figure's painter kept loaded for the next figure of this process with the same scene (issue 45).

A notebook or a script that makes figure after figure of one scene (the same atlas, template,
surface, image settings and scene layers; only the values change, as for the rows of a table or
the volumes of a study) would start a renderer and upload the scene's buffers for each figure.
:func:`kept_painter` gives the figure the painter kept from the figure before when its scene is the
same, already loaded: ~0.3 s of CPU less on a figure of two 1200x900 views (docs/benchmarks.md).

One painter is kept, the last: a figure of another scene closes it and keeps its own,
:func:`release` closes it, and so does the process's exit. While one figure draws with it (until
:func:`put_back`), a figure made meanwhile (another thread) draws with its own painter. Path-traced
(``quality="high"``) painters are not kept: each holds Blender objects, and a render of seconds gains
nothing from it.
"""

from __future__ import annotations

import atexit
import hashlib
import threading
from typing import Any

from brainpainter.io.memo import file_key
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.painter_spec import PainterSpec

_KEPT: dict[str, Painter] = {}
_IN_USE: set[str] = set()  # the key of the kept painter while a figure draws with it
_LOCK = threading.Lock()
_AT_EXIT: list[bool] = []


def scene_key(painter: Painter, template: Any = None) -> str:
    """What makes `painter`'s scene: its spec (atlas, template, surface, hidden regions, settings,
    renderer, colouring, contours and scene layers, pickled), the renderer class registered under its
    name, and the template's manifest file as it is on disk now (a rewritten template is another scene)."""
    from brainpainter.atlas import registry

    spec = PainterSpec.of(painter, template)
    klass = registry.renderers.get(painter.renderer)
    manifest = painter.scene.template.path / "manifest.json"
    on_disk = repr(file_key(manifest)) if manifest.is_file() else ""
    return hashlib.sha256(f"{spec.token}|{id(klass)}|{on_disk}".encode()).hexdigest()


def kept_painter(painter: Painter, template: Any = None) -> Painter:
    """The kept painter of `painter`'s scene if there is one (loaded), else `painter`, now kept.

    Parameters
    ----------
    painter : Painter
        A new, not loaded painter of the run (:meth:`~brainpainter.rendering.checked_run.Run.painter`).
    template : str or Template, optional
        What the caller gave as the template (as :class:`PainterSpec` takes it).
    """
    if painter.settings.quality == "high":
        return painter
    key = scene_key(painter, template)
    with _LOCK:
        if _IN_USE:  # the kept painter draws another figure (another thread): this one draws alone
            return painter
        if key not in _KEPT:
            _close_kept()
            _KEPT[key] = painter
        if not _AT_EXIT:
            atexit.register(release)
            _AT_EXIT.append(True)
        _IN_USE.add(key)
        return _KEPT[key]


def put_back(painter: Painter) -> None:
    """The figure that drew with the kept `painter` is done with it: the next figure may draw with it."""
    with _LOCK:
        _IN_USE.difference_update(k for k, p in _KEPT.items() if p is painter)


def is_kept(painter: Painter) -> bool:
    """Whether `painter` is the kept one (a run that drew with it leaves it open)."""
    with _LOCK:
        return any(p is painter for p in _KEPT.values())


def release() -> None:
    """Close the kept painter, if any (its renderer and buffers freed)."""
    with _LOCK:
        _close_kept()
        _IN_USE.clear()


def _close_kept() -> None:
    for painter in _KEPT.values():
        painter.close()
    _KEPT.clear()
