"""Cycles (``quality="high"``): render engine, lights and colour management of a Blender scene.

The default draw path does not use a Blender scene (see
:mod:`brainpainter_blender.gpu_draw`); Cycles path-traces ``high`` quality
with default shading, with three soft lights that follow the camera. Colour
management is ``Standard`` with no look, exposure 0 and gamma 1 (no
Filmic/AgX tone mapping), so hues are preserved.
"""

from __future__ import annotations

from brainpainter.rendering.scene import RenderSettings
from brainpainter_blender.materials import srgb_to_linear

#: Cycles samples for quality ``high`` (denoised).
CYCLES_SAMPLES = 16
#: Fixed Cycles seed: the same input gives the same pixels.
CYCLES_SEED = 0

# Cycles lights, in camera space (x right, y up, z towards the viewer):
# (name, direction the light comes from, strength in W/m^2 for a sun, angle).
# A sun of strength pi lights a facing white diffuse surface to exactly 1.
_CYCLES_SUNS = (
    ("key", (-0.6, 0.7, 1.0), 1.8, 0.35),
    ("fill", (0.8, -0.2, 0.8), 0.6, 0.8),
    ("rim", (0.0, 0.6, -1.0), 0.5, 0.5),
)
_CYCLES_AMBIENT = 0.25


def configure(bpy, scene, settings: RenderSettings) -> None:
    """Set `scene`'s engine, resolution, colour management and lighting.

    Parameters
    ----------
    bpy : module
    scene : bpy.types.Scene
    settings : brainpainter.rendering.scene.RenderSettings
    """
    render = scene.render
    render.resolution_x, render.resolution_y = int(settings.width), int(settings.height)
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.dither_intensity = 0.0  # dithering adds noise: colours would not be exact
    render.film_transparent = settings.background is None
    render.use_compositing = False
    render.use_sequencer = False
    view = scene.view_settings
    view.view_transform = "Standard"
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    view.use_curve_mapping = False
    scene.display_settings.display_device = "sRGB"

    world = scene.world or bpy.data.worlds.new(f"{scene.name}:world")
    scene.world = world
    background = settings.background if settings.background is not None else (1.0, 1.0, 1.0)
    world.color = srgb_to_linear(background)

    _configure_cycles(bpy, scene, world, background)


def uses_cycles(settings: RenderSettings) -> bool:
    """Cycles draws ``high`` quality, except flat shading: unlit colours need no
    path tracing, so those come from the gpu path with 3x3 supersampling."""
    return settings.quality == "high" and settings.shading != "flat"


def _configure_cycles(bpy, scene, world, background) -> None:
    scene.render.engine = "CYCLES"
    scene.render.use_persistent_data = True  # keep the BVH between images
    cycles = scene.cycles
    cycles.device = "GPU" if _enable_gpu(bpy) else "CPU"
    cycles.samples = CYCLES_SAMPLES
    cycles.use_adaptive_sampling = False
    cycles.seed = CYCLES_SEED
    cycles.use_animated_seed = False
    cycles.use_denoising = True
    cycles.denoiser = "OPENIMAGEDENOISE"
    cycles.denoising_input_passes = "RGB_ALBEDO_NORMAL"
    cycles.denoising_prefilter = "FAST"
    cycles.denoising_quality = "FAST"
    cycles.max_bounces = 3
    cycles.diffuse_bounces = 1
    cycles.glossy_bounces = 1
    cycles.transparent_max_bounces = 8
    cycles.transmission_bounces = 0
    cycles.volume_bounces = 0
    cycles.caustics_reflective = cycles.caustics_refractive = False
    _world_shader(world, srgb_to_linear(background))


def _world_shader(world, linear_rgb) -> None:
    """Uniform white ambient light; the camera sees `linear_rgb` instead.

    (Set through a Light Path node rather than ``world.cycles_visibility``,
    whose update callback needs the context scene to have a world.)
    """
    tree = world.node_tree
    nodes = tree.nodes
    nodes.clear()
    out = nodes.new("ShaderNodeOutputWorld")
    ambient = nodes.new("ShaderNodeBackground")
    ambient.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    ambient.inputs["Strength"].default_value = _CYCLES_AMBIENT
    seen = nodes.new("ShaderNodeBackground")
    seen.inputs["Color"].default_value = (*linear_rgb, 1.0)
    seen.inputs["Strength"].default_value = 1.0
    path = nodes.new("ShaderNodeLightPath")
    mix = nodes.new("ShaderNodeMixShader")
    tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    tree.links.new(ambient.outputs["Background"], mix.inputs[1])
    tree.links.new(seen.outputs["Background"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])


def _enable_gpu(bpy) -> bool:
    """Turn on the first GPU backend Cycles finds; False if there is none."""
    try:
        prefs = bpy.context.preferences.addons["cycles"].preferences
    except (KeyError, AttributeError):  # pragma: no cover
        return False
    for backend in ("OPTIX", "CUDA", "HIP", "METAL", "ONEAPI"):
        try:
            prefs.compute_device_type = backend
        except TypeError:
            continue
        prefs.refresh_devices()
        gpus = [d for d in prefs.devices if d.type == backend]
        if gpus:
            for d in prefs.devices:
                d.use = d.type == backend
            return True
    prefs.compute_device_type = "NONE"
    return False


def add_camera_lights(bpy, scene, camera_obj, collection) -> list:
    """Sun lamps parented to the camera, so Cycles light follows the view.

    Returns
    -------
    list of bpy.types.Object
    """
    from mathutils import Vector

    lamps = []
    for name, direction, strength, angle in _CYCLES_SUNS:
        light = bpy.data.lights.new(f"{scene.name}:{name}", type="SUN")
        light.energy = strength
        light.angle = angle
        obj = bpy.data.objects.new(f"{scene.name}:{name}", light)
        # A sun shines down its local -z; aim local +z at where the light comes from.
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector(direction).normalized().to_track_quat("Z", "Y")
        obj.parent = camera_obj
        collection.objects.link(obj)
        lamps.append(obj)
    return lamps
