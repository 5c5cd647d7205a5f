"""A GPU context for Blender's ``gpu`` module in background mode (``bpy`` as a Python module).

In background mode Blender refuses ``gpu`` drawing ("GPU functions for drawing
are not available in background mode") except inside a ``RenderEngine`` whose
``bl_use_gpu_context`` is true. So a tiny render engine is registered once per
process and started with ``bpy.ops.render.render()`` on a 4x4-pixel dummy
scene (about 0.3 ms); each call runs one Python function with a GPU context
current (:func:`in_gpu_context`). Blender's lean start is enough for it
(``_bpy.import_bpy(full=False)``); when a full start later resets Blender to
its factory scene, which deletes the dummy scene, the next call makes it again.
"""

from __future__ import annotations

from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.io.interrupts import held
from brainpainter_blender import _bpy

_engine: dict[str, Any] = {}


def _engine_class():
    import bpy

    class BrainPainterGpuEngine(bpy.types.RenderEngine):
        """Runs queued Python functions while Blender holds a GPU context (background mode)."""

        bl_idname = "BRAINPAINTER_GPU"
        bl_label = "brainpainter gpu"
        bl_use_gpu_context = True

        def render(self, depsgraph):
            job = _engine.pop("job", None)
            if job is None:
                return
            try:
                _engine["result"] = job()
            except BaseException as exc:  # re-raised outside Blender's call
                _engine["error"] = exc

    return BrainPainterGpuEngine


def in_gpu_context(job):
    """Run ``job()`` with Blender's GPU context current and return its result.

    Call with :data:`brainpainter_blender._bpy.LOCK` held.
    """
    bpy = _bpy.import_bpy(full=False)
    if "class" not in _engine:
        _engine["class"] = _engine_class()
        bpy.utils.register_class(_engine["class"])
    if bpy.data.scenes.get(_engine.get("scene", "")) is None:  # the first call, or a factory reset since
        scene = bpy.data.scenes.new("brainpainter:gpu")
        scene.render.engine = _engine["class"].bl_idname
        scene.render.resolution_x = scene.render.resolution_y = 4
        scene.render.resolution_percentage = 100
        scene.render.use_compositing = scene.render.use_sequencer = False
        cam = bpy.data.objects.new("brainpainter:gpu-camera", bpy.data.cameras.new("brainpainter:gpu-camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
        _engine["scene"] = scene.name
    _engine["job"] = job
    # A signal during Blender's render operator is kept until it returns (io/interrupts.held): raised
    # inside Blender's call stack it was swallowed or left the job queued, and a later call drew with a
    # closed renderer. The draw takes a fraction of a second, so the run still stops at once.
    with held(), _bpy.quiet() as log:
        try:
            bpy.ops.render.render(scene=_engine["scene"])
            failed = None
        except RuntimeError as exc:
            failed = exc
        finally:
            _engine.pop("job", None)
    if failed is not None:
        text = " ".join("".join(log).split())[-300:]
        raise BrainPainterError(f"Blender's GPU drawing failed to start: {failed} {text}".strip())
    if "error" in _engine:
        raise _engine.pop("error")
    return _engine.pop("result", None)
