"""Materials: one per region, recoloured in place for every image.

Used by the Cycles path (``quality="high"``). A region material carries its
colour in the Principled BSDF's base colour (and ``diffuse_color``, which
Blender's viewport shows). Blender stores both as scene-linear
values, so sRGB inputs are linearised here; with the ``Standard`` view
transform the rendered pixel is the sRGB colour again.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from brainpainter.rendering.geometry import GLASS_COLOR

# Cycles' unlit glass is darkened to read like the lit glass of the default draw path.
_GLASS_CYCLES_SHADE = 0.6
# Surface finish in Cycles: matte, like a plastic model.
_ROUGHNESS = 0.6
_SPECULAR = 0.25


def srgb_to_linear(rgb: Sequence[float]) -> tuple[float, float, float]:
    """The IEC 61966-2-1 sRGB transfer function inverted.

    Parameters
    ----------
    rgb : sequence of float, shape (3,)
        sRGB 0-1 (clipped to that range).

    Returns
    -------
    tuple of float, shape (3,)
        Linear-light values 0-1.
    """
    c = np.clip(np.asarray(rgb, dtype=float)[:3], 0.0, 1.0)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return (float(lin[0]), float(lin[1]), float(lin[2]))


def _node_tree(material):
    if material.node_tree is None:  # pragma: no cover - Blender < 5 creates no nodes by default
        material.use_nodes = True
    return material.node_tree


def _principled(material):
    for node in _node_tree(material).nodes:
        if node.bl_idname == "ShaderNodeBsdfPrincipled":
            return node
    raise RuntimeError(f"material {material.name!r} has no Principled BSDF node")  # pragma: no cover


def new_region_material(bpy, name: str):
    """A matte material whose colour :func:`set_color` changes.

    Parameters
    ----------
    bpy : module
    name : str
        Datablock name (Blender may add a suffix if taken).
    """
    mat = bpy.data.materials.new(name)
    mat.roughness = _ROUGHNESS
    mat.specular_intensity = _SPECULAR
    bsdf = _principled(mat)
    bsdf.inputs["Roughness"].default_value = _ROUGHNESS
    bsdf.inputs["Specular IOR Level"].default_value = _SPECULAR
    return mat


def new_glass_material(bpy, name: str, opacity: float):
    """A light, semi-transparent material for the glass brain.

    In Cycles the glass is an unlit grey mixed with full transparency (no
    lighting to sample, hence no noise), more opaque where the surface turns
    away from the camera, as the default draw path's glass.
    """
    mat = bpy.data.materials.new(name)
    mat.surface_render_method = "BLENDED"
    linear = srgb_to_linear(GLASS_COLOR)
    opacity = float(np.clip(opacity, 0.0, 1.0))
    mat.diffuse_color = (*linear, opacity)
    tree = _node_tree(mat)
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    mix, emission = _glass_nodes(tree, opacity)
    emission.inputs["Color"].default_value = (*(c * _GLASS_CYCLES_SHADE for c in linear), 1.0)
    tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return mat


def _glass_nodes(tree, opacity: float):
    """Unlit colour (an emission) mixed with transparency: `opacity` facing the camera, up to 2.5 x
    `opacity` at grazing angles. Returns the mix node and the emission node (whose colour is set)."""
    nodes, links = tree.nodes, tree.links
    emission = nodes.new("ShaderNodeEmission")
    emission.name = "bp_glass_emission"
    emission.inputs["Strength"].default_value = 1.0
    clear = nodes.new("ShaderNodeBsdfTransparent")
    facing = nodes.new("ShaderNodeLayerWeight")
    facing.inputs["Blend"].default_value = 0.5
    edge = nodes.new("ShaderNodeMapRange")
    edge.clamp = True
    edge.inputs["To Min"].default_value = opacity
    edge.inputs["To Max"].default_value = min(1.0, 2.5 * opacity)
    links.new(facing.outputs["Facing"], edge.inputs["Value"])
    mix = nodes.new("ShaderNodeMixShader")
    mix.name = "bp_glass"
    links.new(edge.outputs["Result"], mix.inputs["Fac"])
    links.new(clear.outputs["BSDF"], mix.inputs[1])
    links.new(emission.outputs["Emission"], mix.inputs[2])
    return mix, emission


def set_glass(material, opacity: float | None) -> None:
    """Draw a region material as glass in its own colour (`opacity`: the cortex of a cortex view
    with ``--cortex glass``, as the default draw path does), or lit and opaque again (None).

    The glass is the glass brain's recipe (:func:`new_glass_material`) in the region's colour:
    unlit, so path tracing adds no noise to it.
    """
    tree = _node_tree(material)
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    if opacity is None:
        tree.links.new(_principled(material).outputs["BSDF"], out.inputs["Surface"])
        return
    if tree.nodes.get("bp_glass") is None:
        _glass_nodes(tree, float(np.clip(opacity, 0.0, 1.0)))
        _set_glass_color(material, material.diffuse_color[:3])
    tree.links.new(tree.nodes["bp_glass"].outputs["Shader"], out.inputs["Surface"])


def _set_glass_color(material, linear: Sequence[float]) -> None:
    emission = _node_tree(material).nodes.get("bp_glass_emission")
    if emission is not None:
        # the region's own colour (the grey glass brain is shaded down; a colour would turn muddy)
        emission.inputs["Color"].default_value = (*linear[:3], 1.0)


def set_color(material, rgb: Sequence[float]) -> None:
    """Set an opaque region material to the sRGB colour `rgb` (0-1)."""
    value = (*srgb_to_linear(rgb), 1.0)
    material.diffuse_color = value
    _principled(material).inputs["Base Color"].default_value = value
    _set_glass_color(material, value)
