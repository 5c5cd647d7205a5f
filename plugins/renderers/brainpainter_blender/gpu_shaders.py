"""GLSL sources and compiled shaders of the ``gpu`` draw path (:mod:`brainpainter_blender.gpu_draw`).

Shaders are compiled once per process, inside a GPU context, and dropped
before Blender's own exit handler (which reports GPU blocks still held).
"""

from __future__ import annotations

import atexit
from typing import Any

#: Values of the part shader's ``mode``: lit opaque surface, or glass.
MODE_LIT, MODE_GLASS = 0, 1

#: Width of the 2-D palette texture: slot ``i`` is texel ``(i % PALETTE_WIDTH, i / PALETTE_WIDTH)``.
PALETTE_WIDTH = 4096

_VERTEX = """
void main()
{
  int slot = int(pal + 0.5);
  vec3 base = texelFetch(palette, ivec2(slot % PALETTE_WIDTH, slot / PALETTE_WIDTH), 0).rgb;
  vec3 n = normalize(nrm);
  if (dot(n, back) < 0.0) {
    n = -n;  /* seen from inside (a hole, the cut medial wall): light the side we see */
  }
  /* baked ambient occlusion (1 = open sky): darkens the ambient light fully and the direct
     lights partly, so folds read in every colour; a multiplier in linear light keeps the hue */
  float occ = mix(1.0, ao, ao_strength);
  float direct = key * max(dot(n, key_dir), 0.0) + fill * max(dot(n, fill_dir), 0.0);
  float shade = ambient * occ + direct * mix(1.0, occ, ao_direct);
  shade *= 1.0 - sulc_strength * sulc;
  /* an S-curve around mid-grey: crowns towards full colour, folds towards dark; 0 and 1 stay */
  float s = clamp(shade, 0.0, 1.0);
  shade = mix(shade, s * s * (3.0 - 2.0 * s), contrast);
  float facing = clamp(abs(dot(normalize(nrm), back)), 0.0, 1.0);
  /* rim: silhouettes darken, so a structure in front stands out of the one behind it */
  float edge = 1.0 - facing;
  shade *= 1.0 - rim * edge * edge;
  vec3 c = base * shade;
  if (mode == 1) {
    /* Fresnel-like glass: nearly clear facing the camera, opaque towards the outline (a shell) */
    float a = clamp(glass_alpha + (glass_edge * glass_alpha - glass_alpha) * edge
                    + glass_rim * edge * edge * edge, 0.0, 1.0);
    color = vec4(base * a, a);
  } else {
    color = vec4(c, 1.0);
  }
  gl_Position = mvp * vec4(pos, 1.0);
}
"""

_FRAGMENT = """
void main()
{
  fragColor = color;
}
"""

_RESOLVE_VERTEX = """
void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
"""

_RESOLVE_FRAGMENT = """
void main()
{
  /* FACTOR (the supersampling factor) is a compile-time constant, so the loops unroll */
  ivec2 p = ivec2(gl_FragCoord.xy);
  /* flipped: row 0 of the read-back is the image's top row */
  ivec2 src = ivec2(p.x, out_height - 1 - p.y) * FACTOR;
  vec4 sum = vec4(0.0);
  for (int j = 0; j < FACTOR; j++) {
    for (int i = 0; i < FACTOR; i++) {
      sum += texelFetch(image, src + ivec2(i, j), 0);
    }
  }
  sum *= 1.0 / float(FACTOR * FACTOR);
  /* linear light out: the sRGB target encodes it */
  fragColor = vec4(sum.a > 0.0 ? sum.rgb / sum.a : vec3(0.0), sum.a);
}
"""


_shaders: dict[Any, Any] = {}


def part_shader() -> Any:
    """The shader of every part (compiled once per process, in a GPU context)."""
    if "part" in _shaders:
        return _shaders["part"]
    import gpu

    iface = gpu.types.GPUStageInterfaceInfo("brainpainter_part")
    iface.smooth("VEC4", "color")
    info = gpu.types.GPUShaderCreateInfo()
    info.define("PALETTE_WIDTH", str(PALETTE_WIDTH))
    for kind, name in (("MAT4", "mvp"), ("VEC3", "back"), ("VEC3", "key_dir"), ("VEC3", "fill_dir"),
                       ("FLOAT", "ambient"), ("FLOAT", "key"), ("FLOAT", "fill"),
                       ("FLOAT", "sulc_strength"), ("FLOAT", "glass_alpha"), ("FLOAT", "glass_edge"),
                       ("FLOAT", "ao_strength"), ("FLOAT", "ao_direct"), ("FLOAT", "rim"),
                       ("FLOAT", "glass_rim"), ("FLOAT", "contrast"), ("INT", "mode")):
        info.push_constant(kind, name)
    info.sampler(0, "FLOAT_2D", "palette")
    info.vertex_in(0, "VEC3", "pos")
    info.vertex_in(1, "VEC3", "nrm")
    info.vertex_in(2, "FLOAT", "pal")
    info.vertex_in(3, "FLOAT", "sulc")
    info.vertex_in(4, "FLOAT", "ao")
    info.vertex_out(iface)
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source(_VERTEX)
    info.fragment_source(_FRAGMENT)
    return _keep("part", gpu.shader.create_from_info(info), iface)


def resolve_shader(factor: int) -> Any:
    """The resolve shader for one supersampling factor (compiled once per process and factor)."""
    key = ("resolve", factor)
    if key in _shaders:
        return _shaders[key]
    import gpu

    info = gpu.types.GPUShaderCreateInfo()
    info.define("FACTOR", str(int(factor)))
    info.push_constant("INT", "out_height")
    info.sampler(0, "FLOAT_2D", "image")
    info.vertex_in(0, "VEC2", "pos")
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source(_RESOLVE_VERTEX)
    info.fragment_source(_RESOLVE_FRAGMENT)
    return _keep(key, gpu.shader.create_from_info(info))


def _keep(key: Any, shader: Any, *extra: Any) -> Any:
    if not _shaders:
        # Drop them before Blender's own exit handler, which reports GPU blocks still held.
        atexit.register(_shaders.clear)
    _shaders[key] = shader
    for i, obj in enumerate(extra):
        _shaders[(key, i)] = obj
    return shader
