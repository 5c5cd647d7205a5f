"""The Blender renderer: load a scene once, then recolour, re-aim and render.

Two draw paths behind one class. The default is Blender's ``gpu`` module
(:mod:`brainpainter_blender.gpu_draw`): the scene's geometry is uploaded once
as indexed batches and each image uploads a palette, draws, anti-aliases
the edges and reads the pixels back. ``quality="high"`` with default
shading path-traces with Cycles instead (GPU when one is present): that path
builds Blender objects with one material per region and recolours the
materials. What is drawn and from where comes from core
(``scene.geometry``), the same for both paths. bpy calls are serialised by
one process-wide lock; ``close`` frees everything the renderer created.
"""

from __future__ import annotations

import itertools
import shutil
import tempfile
import weakref
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from PIL import Image

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.geometry import Palette
from brainpainter.rendering.scene import RGB, BlankRenderError, Scene, nothing_drawn
from brainpainter.rendering.views import View
from brainpainter_blender import _bpy, lighting, materials, scene_builder

_ids = itertools.count()


class BlenderRenderer:
    """Render a :class:`~brainpainter.rendering.scene.Scene` with Blender (``bpy``).

    Parameters
    ----------
    scene : brainpainter.rendering.scene.Scene
        Loaded once: ``scene.geometry`` (both hemispheres' cortex for
        ``scene.surface`` and ``scene.labels``, the subcortical structures and
        the glass hulls).

    Examples
    --------
    >>> r = BlenderRenderer(scene)                      # doctest: +SKIP
    >>> rgba = r.render(Palette({"Left-insula": (1, 0, 0)}, scene.geometry),
    ...                 get_view("lateral-left"))       # doctest: +SKIP
    >>> r.close()                                       # doctest: +SKIP
    """

    name = "blender"

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.cycles = lighting.uses_cycles(scene.settings)
        self._bpy = bpy = _bpy.import_bpy(full=self.cycles)  # the gpu path: Blender's lean start
        self._tag = f"bp{next(_ids)}"
        self._closed = False
        self._colors: dict[int, tuple[float, ...]] = {}
        self._as_glass: dict[str, bool] = {}  # Cycles: the cortex parts drawn as glass (--cortex glass)
        self._gpu = None
        #: the renderer contract's capability: Cycles draws a tract part's tubes, the gpu path its centrelines
        self.draws_tubes = self.cycles
        if self.cycles and getattr(scene, "coloring", "regions") == "vertices":
            raise BrainPainterError(
                "per-vertex maps are drawn by the gpu path, not by Cycles (--quality high with smooth "
                "shading); use --quality default, or --quality high --shading flat.")
        if self.cycles and scene.settings.outline_width > 0:
            raise BrainPainterError(
                "region outlines (--outline) are drawn by the gpu path, not by Cycles (--quality high with "
                "smooth shading); use --quality default, or --quality high --shading flat.")
        with _bpy.LOCK:
            try:
                if self.cycles:
                    self._tmp = Path(tempfile.mkdtemp(prefix="brainpainter-blender-"))
                    self._file = self._tmp / "render.tif"
                    # The temporary folder goes even if close() is never called.
                    weakref.finalize(self, shutil.rmtree, self._tmp, True)
                    with _bpy.quiet():  # Cycles prints notices while probing for GPUs
                        self._build(bpy)
                else:
                    from brainpainter_blender.gpu_draw import GpuDraw

                    self._gpu = GpuDraw(scene.geometry, scene.settings)
            except BaseException:
                self._free()
                raise

    def _build(self, bpy) -> None:
        settings = self.scene.settings
        self._bscene = bscene = bpy.data.scenes.new(self._tag)
        lighting.configure(bpy, bscene, settings)
        image = bscene.render.image_settings
        # Uncompressed 8-bit TIFF: the quickest lossless round trip (straight alpha).
        image.file_format = "TIFF"
        image.tiff_codec = "NONE"
        image.color_mode = "RGBA"
        image.color_depth = "8"
        cam_data = bpy.data.cameras.new(f"{self._tag}:camera")
        cam_data.type = "ORTHO"
        cam_data.sensor_fit = "HORIZONTAL"
        self._camera = bpy.data.objects.new(f"{self._tag}:camera", cam_data)
        bscene.collection.objects.link(self._camera)
        bscene.camera = self._camera
        self._lamps = lighting.add_camera_lights(bpy, bscene, self._camera, bscene.collection)
        self._parts = scene_builder.build(bpy, self.scene, self._tag, bscene.collection)

    # -- per image -------------------------------------------------------------
    def render(self, palette: Mapping[str, RGB], view: View) -> np.ndarray:
        """Render one image.

        Parameters
        ----------
        palette : brainpainter.rendering.geometry.Palette, or a mapping of str to (r, g, b)
            sRGB 0-1 colour per region key; cortex regions without a colour
            are drawn in ``scene.medial_wall_color``, subcortical ones in a
            neutral light grey.
        view : brainpainter.rendering.views.View

        Returns
        -------
        ndarray of uint8, shape (height, width, 4)
            RGBA, row 0 at the top, sRGB, straight alpha.
        """
        if self._closed:
            raise BrainPainterError("this BlenderRenderer was closed; create a new one to render.")
        if not isinstance(palette, Palette):
            palette = Palette(palette, self.scene.geometry)
        with _bpy.LOCK:
            if self._gpu is not None:
                pixels = self._gpu.render(palette.rgb, view)
            else:
                if view.clip:
                    raise BrainPainterError(
                        f"view {view.name!r} cuts the brain open (--clip, cutaway views), which the gpu path "
                        "draws, not Cycles (--quality high with smooth shading); use --quality default, or "
                        "--quality high --shading flat.")
                if view.content == "flat":
                    raise BrainPainterError(
                        f"view {view.name!r} (a flat map) is drawn by the gpu path, not by Cycles (--quality "
                        "high with smooth shading); use --quality default, or --quality high --shading flat.")
                self._show(view)
                self._recolor(palette)
                self._aim(view)
                pixels = self._render_pixels()
        _bpy.release_memory()
        # never an empty image with exit 0: a new bpy release once drew nothing, silently
        if nothing_drawn(pixels, self.scene.settings.background):
            raise BlankRenderError.of(view, *_bpy.version_hint())
        return pixels

    def _show(self, view: View) -> None:
        shown = {p.name: p.kind for p in self.scene.geometry.visible(view)}  # nothing shown: an error
        glass = self.scene.settings.glass_opacity
        for part in self._parts:
            on = part.name in shown
            if part.obj.hide_render == on:
                part.obj.hide_render = not on
            if part.kind == "cortex":  # a cortex view with --cortex glass: see-through, in its colours
                as_glass = shown.get(part.name) == "glass"
                if self._as_glass.get(part.name, False) != as_glass:
                    for _, mat in part.slots:
                        materials.set_glass(mat, glass if as_glass else None)
                    obj = part.obj  # as glass, it neither shadows nor reflects onto the tracts inside
                    obj.visible_shadow = obj.visible_diffuse = obj.visible_glossy = not as_glass
                    self._as_glass[part.name] = as_glass

    def _recolor(self, palette: Palette) -> None:
        rgb = palette.rgb
        for part in self._parts:
            for slot, mat in part.slots:
                color = tuple(float(c) for c in rgb[slot])
                if self._colors.get(id(mat)) != color:
                    materials.set_color(mat, color)
                    self._colors[id(mat)] = color

    def _aim(self, view: View) -> None:
        from mathutils import Matrix

        settings = self.scene.settings
        pose = self.scene.geometry.camera(view, settings.width / settings.height)
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = pose.rotation, pose.location
        self._camera.matrix_world = Matrix(m.tolist())
        data = self._camera.data
        data.ortho_scale = pose.ortho_scale
        data.clip_start, data.clip_end = pose.clip_start, pose.clip_end

    def _render_pixels(self) -> np.ndarray:
        bpy = self._bpy
        with _bpy.quiet() as log:
            try:
                bpy.ops.render.render(write_still=False, scene=self._bscene.name)
                bpy.data.images["Render Result"].save_render(str(self._file), scene=self._bscene)
                failed = None
            except (RuntimeError, KeyError) as exc:
                failed = exc
        if failed is not None:
            text = " ".join("".join(log).split())[-300:]
            raise BrainPainterError(f"Blender failed to render: {failed} {text}".strip())
        with Image.open(self._file) as im:
            return np.array(im.convert("RGBA"))

    # -- lifetime --------------------------------------------------------------
    def close(self) -> None:
        """Delete this renderer's Blender data and temporary files (idempotent)."""
        if self._closed:
            return
        with _bpy.LOCK:
            self._free()

    def _free(self) -> None:
        self._closed = True
        if self._gpu is not None:
            self._gpu.close()
            self._gpu = None
        if not self.cycles:
            return
        bpy = self._bpy
        prefix = self._tag + ":"
        for coll in (bpy.data.objects, bpy.data.meshes, bpy.data.materials,
                     bpy.data.cameras, bpy.data.lights, bpy.data.worlds):
            for block in [b for b in coll if b.name.startswith(prefix)]:
                coll.remove(block)
        scene = bpy.data.scenes.get(self._tag)
        if scene is not None:
            bpy.data.scenes.remove(scene)
        shutil.rmtree(self._tmp, ignore_errors=True)
        self._colors.clear()

    def __enter__(self) -> BlenderRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

