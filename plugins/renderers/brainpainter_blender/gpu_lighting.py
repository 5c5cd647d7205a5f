"""The default draw path's lights: camera-relative, per vertex, in linear light.

:class:`Lighting` is one set of lights; :data:`LIGHTING` the ``--lighting`` presets, :data:`FLAT`
unlit (``--shading flat``, a flat map), :func:`for_maps` a preset as it falls on a map's cortex.
The shaders that apply them are in :mod:`brainpainter_blender.gpu_shaders`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Lighting:
    """Camera-relative lights, in linear light (a white surface facing a light of 1 is 1).

    Attributes
    ----------
    ambient : float
    key, fill : float
        Strength of the key and fill lights.
    key_dir, fill_dir : tuple of float, shape (3,)
        Direction the light comes from, in camera space (x right, y up, z towards the viewer).
    sulc : float
        Darkening at the bottom of sulci (0 = none, 1 = black).
    lit : bool
        False: unlit palette colours (times the sulcal darkening).
    occlusion : float
        Weight of the template's baked ambient occlusion (0 = ignored, 1 = full) on the ambient light.
    occlusion_direct : float
        Share of that occlusion that also dims the key and fill lights (0-1).
    occlusion_open : float
        Baked occlusion at or above which a vertex counts as fully open (the walls of a
        sulcus's mouth stay bright; only what lies deeper darkens).
    contrast : float
        Weight of an S-curve (smoothstep) on the lighting: lit crowns nearer their full colour,
        folds darker, never above 1 (0 = linear).
    rim : float
        Darkening of the outline of subcortical structures (0 = none; at a grazing angle the
        colour is multiplied by ``1 - rim``).
    """

    ambient: float
    key: float
    fill: float
    key_dir: tuple[float, float, float] = (-0.45, 0.55, 0.70)
    fill_dir: tuple[float, float, float] = (0.60, -0.20, 0.77)
    sulc: float = 0.0
    lit: bool = True
    occlusion: float = 0.0
    occlusion_direct: float = 0.0
    occlusion_open: float = 1.0
    contrast: float = 0.0
    rim: float = 0.0


#: Lighting per ``--lighting`` preset; ``--shading flat`` is always unlit and exact.
LIGHTING = {
    # ambient + key + fill peak near 1 (a facing surface keeps its colour, no clipping to white
    # or to a pure hue on lit slopes); the baked occlusion darkens what lies deeper than a
    # sulcus's mouth and the S-curve spreads lightness, so the folds read in a saturated colour
    # (L* p90 - p10 >= 25 for pure red) while the median white surface stays near-white
    "studio": Lighting(ambient=0.5, key=0.5, fill=0.05, occlusion=1.0, occlusion_direct=1.0,
                       occlusion_open=0.8, contrast=1.0, rim=0.5),
    "soft": Lighting(ambient=0.62, key=0.36, fill=0.05, occlusion=1.0, occlusion_direct=0.5,
                     occlusion_open=0.8, contrast=0.5, rim=0.4),
    "sulc": Lighting(ambient=0.5, key=0.5, fill=0.05, sulc=0.3, occlusion=1.0, occlusion_direct=1.0,
                     occlusion_open=0.8, contrast=1.0, rim=0.5),
    "flat-studio": Lighting(ambient=1.0, key=0.0, fill=0.0, sulc=0.35, lit=False, occlusion=0.5,
                            occlusion_open=0.8),
}
FLAT = Lighting(ambient=1.0, key=0.0, fill=0.0, lit=False)
#: A map's cortex (colours per vertex) under a lit preset: the share of the key light turned into
#: ambient light (a facing surface stays as bright), and the weights kept of the occlusion (on the
#: ambient, on the direct light) and of the S-curve. A map's colours carry its values and darkening
#: reads as another value: ``benchmarks/map_truth.py`` reads a constant map back through the colour
#: map in CIELAB (docs/maps.md, "Lighting").
MAP_LIGHT = {"key_to_ambient": 0.3, "occlusion": 0.6, "occlusion_direct": 0.3, "contrast": 0.3}


def for_maps(light: Lighting) -> Lighting:
    """`light` as it falls on a map's cortex: the relief kept, lightness moved less (:data:`MAP_LIGHT`);
    unlit presets (``flat-studio``, flat shading) as they are."""
    if not light.lit:
        return light
    m = MAP_LIGHT
    return replace(light, ambient=light.ambient + m["key_to_ambient"] * light.key,
                   key=(1.0 - m["key_to_ambient"]) * light.key, occlusion=m["occlusion"] * light.occlusion,
                   occlusion_direct=m["occlusion_direct"] * light.occlusion_direct,
                   contrast=m["contrast"] * light.contrast)
