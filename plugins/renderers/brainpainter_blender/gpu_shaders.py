"""GLSL sources and compiled shaders of the ``gpu`` draw path (:mod:`brainpainter_blender.gpu_draw`).

Shaders are compiled once per process, inside a GPU context, and dropped
before Blender's own exit handler (which reports GPU blocks still held).
"""

from __future__ import annotations

import atexit
from typing import Any

#: Values of the part shader's ``mode``: lit opaque surface, glass, or (a clipped view's variant) the cut
#: face: a cut part's inside, in one colour, lit as the cutting plane.
MODE_LIT, MODE_GLASS, MODE_CAP = 0, 1, 2

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
#if CLIP
  world = pos;
#endif
  gl_Position = mvp * vec4(pos, 1.0);
}
"""

_FRAGMENT = """
void main()
{
#if CLIP
  /* a cutaway (rendering.clip): a fragment on the removed side of every plane is cut away; a cut
     part's inside (its faces turned away, mode 2) is the cut face, lit as the plane nearest it */
  if (clip_on != 0) {
    bool cut = n_clip > 0;
    float nearest = -1e30;
    vec3 normal = vec3(0.0, 0.0, 1.0);
    for (int i = 0; i < 4; i++) {
      if (i < n_clip) {
        float d = dot(clips[i].xyz, world) + clips[i].w;
        if (d <= 0.0) {
          cut = false;
          if (d > nearest) {
            nearest = d;
            normal = clips[i].xyz;
          }
        }
      }
    }
    if (cut) {
      discard;
    }
    if (mode == 2) {
      float shade = ambient + key * max(dot(normal, key_dir), 0.0) + fill * max(dot(normal, fill_dir), 0.0);
      float s = clamp(shade, 0.0, 1.0);
      shade = mix(shade, s * s * (3.0 - 2.0 * s), contrast);
      fragColor = vec4(cap_rgb * shade, 1.0);
      return;
    }
  }
#endif
  fragColor = color;
}
"""

_DEPTH_VERTEX = """
void main()
{
  gl_Position = mvp * vec4(pos, 1.0);  /* as the part shader places it: the same depth */
}
"""

_DEPTH_FRAGMENT = """
void main()
{
  fragColor = vec4(0.0);
}
"""

_RESOLVE_VERTEX = """
void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
"""

_RESOLVE_FRAGMENT = """
#if GLASS
/* the image under the glass's last layer (glass_layers), blended as the glass passes blend */
vec4 fetch(ivec2 q)
{
  vec4 g = texelFetch(glass, q, 0);
  return g + (1.0 - g.a) * texelFetch(image, q, 0);
}
#else
vec4 fetch(ivec2 q)
{
  return texelFetch(image, q, 0);
}
#endif

void main()
{
  /* FACTOR (the supersampling factor) is a compile-time constant, so the loops unroll */
  ivec2 p = ivec2(gl_FragCoord.xy);
  /* flipped: row 0 of the read-back is the image's top row */
  ivec2 src = ivec2(p.x, out_height - 1 - p.y) * FACTOR;
  vec4 sum = vec4(0.0);
  for (int j = 0; j < FACTOR; j++) {
    for (int i = 0; i < FACTOR; i++) {
      sum += fetch(src + ivec2(i, j));
    }
  }
  sum *= 1.0 / float(FACTOR * FACTOR);
#if EDGES
  /* an edge's pixel (FACTOR 1): mixed with its neighbour across the edge by the share of the
     pixel that the other side covers (see edge_aa) */
  vec4 e = texelFetch(edges, src, 0);
  if (e.a > 0.0) {
    ivec2 across = clamp(src + ivec2(round(e.xy * 2.0 - 1.0)), ivec2(0), textureSize(image, 0) - 1);
    sum = mix(sum, fetch(across), e.z);
  }
#endif
  /* linear light out: the sRGB target encodes it */
  fragColor = vec4(sum.a > 0.0 ? sum.rgb / sum.a : vec3(0.0), sum.a);
}
"""


_EDGE_VERTEX = """
void main()
{
  /* the edge in framebuffer pixels: a point on it (anchor) and its direction, the same at both
     ends (pointing right, or up), so the fragment can find its distance from the edge */
  vec4 c = mvp * vec4(pos, 1.0);
  vec4 o = mvp * vec4(other, 1.0);
  vec2 a = (c.xy / c.w * 0.5 + 0.5) * viewport;
  vec2 d = (o.xy / o.w * 0.5 + 0.5) * viewport - a;
  dir = (d.x < 0.0 || (d.x == 0.0 && d.y < 0.0)) ? -d : d;
  anchor = a;
  c.z -= bias * c.w;
  gl_Position = c;
}
"""

_EDGE_FRAGMENT = """
void main()
{
  /* distance from the pixel's centre to the edge along the minor axis: the neighbour on the
     other side covers 0.5 - |distance| of the pixel */
  vec2 off = gl_FragCoord.xy - anchor;
  bool xmajor = abs(dir.x) >= abs(dir.y);
  float dist = xmajor ? off.y - dir.y / dir.x * off.x : off.x - dir.x / dir.y * off.y;
  float w = 0.5 - abs(dist);
  if (w <= 0.0) {
    discard;
  }
  vec2 across = xmajor ? vec2(0.0, dist > 0.0 ? -1.0 : 1.0) : vec2(dist > 0.0 ? -1.0 : 1.0, 0.0);
  fragColor = vec4(across * 0.5 + 0.5, w, 1.0);
}
"""

_BOX_VERTEX = """
void main()
{
  /* a unit square stretched over `box` (x0, y0, x1, y1 in normalised device coordinates) */
  gl_Position = vec4(mix(box.xy, box.zw, pos), 0.0, 1.0);
}
"""

_FILL_FRAGMENT = """
void main()
{
  /* a pixel that only lines' fringes reach takes the slots of a neighbouring line's core */
  ivec2 q = ivec2(gl_FragCoord.xy);
  vec4 at = texelFetch(slots, q, 0);
  if (at.a < 0.5) {
    ivec2 last = textureSize(slots, 0) - 1;
    vec4 n[4] = vec4[4](texelFetch(slots, clamp(q + ivec2(1, 0), ivec2(0), last), 0),
                        texelFetch(slots, clamp(q - ivec2(1, 0), ivec2(0), last), 0),
                        texelFetch(slots, clamp(q + ivec2(0, 1), ivec2(0), last), 0),
                        texelFetch(slots, clamp(q - ivec2(0, 1), ivec2(0), last), 0));
    for (int i = 0; i < 4; i++) {
      at = n[i].a > at.a ? n[i] : at;
    }
  }
  fragColor = at;
}
"""

_COLOUR_FRAGMENT = """
vec3 slot_rgb(float slot)
{
  int i = int(slot + 0.5);
  return texelFetch(palette, ivec2(i % PALETTE_WIDTH, i / PALETTE_WIDTH), 0).rgb;
}

void main()
{
  /* the tracts' layer in this image's colours: the slots' colours times the light (premultiplied) */
  ivec2 q = ivec2(gl_FragCoord.xy);
  vec4 lum = texelFetch(shade, q, 0);
  vec4 at = texelFetch(slots, q, 0);
  fragColor = vec4(mix(slot_rgb(at.r), slot_rgb(at.g), at.b) * lum.r, lum.a);
}
"""

_OVER_FRAGMENT = """
void main()
{
  /* each supersample takes its output pixel of the (premultiplied) layer, blended over it */
  fragColor = texelFetch(layer, ivec2(gl_FragCoord.xy) / FACTOR, 0);
}
"""

_LINE_VERTEX = """
void main()
{
  /* a segment joins an even and an odd point: each point puts its slot in its parity's channel,
     so a fragment can tell both slots and how far along it is (see _LINE_FRAGMENT) */
  even_slot = pal * (1.0 - odd);
  odd_slot = pal * odd;
  towards_odd = odd;
  vec4 c = mvp * vec4(pos, 1.0);
  /* the direction in framebuffer pixels (gl_FragCoord's units) */
  vec2 t = (mvp * vec4(tang, 0.0)).xy * viewport;
  float l = length(t);
  dir = l > 1e-6 ? t / l : vec2(1.0, 0.0);
  /* a streamline's ends reach out by the line's half width (square caps), so a streamline seen
     end-on is a dot as wide as its tube, not nothing */
  c.xy += cap * (half_width + 0.5) * dir * 2.0 / viewport * c.w;
  centre = (c.xy / c.w * 0.5 + 0.5) * viewport;
  gl_Position = c;
}
"""

_LINE_FRAGMENT = """
void main()
{
  /* signed distance from the centreline in pixels: coverage of a line 2 * half_width wide
     (box-filtered, so a line thinner than a pixel fades instead of breaking up) and, lit,
     the normal of a round tube at that point (camera space: x right, y up, z to the viewer) */
  vec2 dn = normalize(dir);
  vec2 off = gl_FragCoord.xy - centre;
  float d = dn.x * off.y - dn.y * off.x;
  float cov = clamp(min(half_width + 0.5 - abs(d), 2.0 * half_width), 0.0, 1.0);
  float u = clamp(d / max(half_width, 0.5), -1.0, 1.0);
  vec3 n = vec3(vec2(-dn.y, dn.x) * u, sqrt(1.0 - u * u));
  float shade = ambient + key * max(dot(n, key_dir), 0.0) + fill * max(dot(n, fill_dir), 0.0);
  float s = clamp(shade, 0.0, 1.0);
  shade = mix(shade, s * s * (3.0 - 2.0 * s), contrast);
  /* colourless: the light and coverage, blended (premultiplied) */
  lit = vec4(shade * cov, 0.0, 0.0, cov);
  /* the colour's slots, replaced by each line that covers half the pixel (the nearest such
     line wins: the farthest streamline is drawn first); alpha 0 leaves them as they are */
  float w_even = 1.0 - towards_odd;
  float even = w_even > 1e-4 ? even_slot / w_even : odd_slot / towards_odd;
  float odd = towards_odd > 1e-4 ? odd_slot / towards_odd : even;
  slot = cov >= 0.5 ? vec4(even, odd, towards_odd, 1.0) : vec4(0.0);
}
"""


_shaders: dict[Any, Any] = {}


#: Push constants of the part shader (GLSL type, name).
_PART_CONSTANTS = (("MAT4", "mvp"), ("VEC3", "back"), ("VEC3", "key_dir"), ("VEC3", "fill_dir"),
                   ("FLOAT", "ambient"), ("FLOAT", "key"), ("FLOAT", "fill"),
                   ("FLOAT", "sulc_strength"), ("FLOAT", "glass_alpha"), ("FLOAT", "glass_edge"),
                   ("FLOAT", "ao_strength"), ("FLOAT", "ao_direct"), ("FLOAT", "rim"),
                   ("FLOAT", "glass_rim"), ("FLOAT", "contrast"), ("INT", "mode"))
#: Vertex attributes of the part shader (GLSL type, name), in their locations' order.
_PART_INPUTS = (("VEC3", "pos"), ("VEC3", "nrm"), ("FLOAT", "pal"), ("FLOAT", "sulc"), ("FLOAT", "ao"))


#: The clipped variant's extra push constants: the planes (columns ``a, b, c, d``: cut where ``a*x + b*y +
#: c*z + d > 0`` for every plane), how many, whether this part is cut, and the cut face's linear colour.
_CLIP_CONSTANTS = (("MAT4", "clips"), ("INT", "n_clip"), ("INT", "clip_on"), ("VEC3", "cap_rgb"))


def part_shader(clip: bool = False) -> Any:
    """The shader of every part (compiled once per process and variant, in a GPU context); `clip`: the
    variant of views with cutaway planes (the world position goes to the fragments, which it cuts)."""
    if clip:
        return _build("part_clip", _VERTEX, _FRAGMENT, defines={"PALETTE_WIDTH": PALETTE_WIDTH, "CLIP": 1},
                      constants=_PART_CONSTANTS + _CLIP_CONSTANTS, samplers=("palette",), inputs=_PART_INPUTS,
                      varyings=(("smooth", "VEC4", "color"), ("smooth", "VEC3", "world")))
    return _build("part", _VERTEX, _FRAGMENT, defines={"PALETTE_WIDTH": PALETTE_WIDTH, "CLIP": 0},
                  constants=_PART_CONSTANTS, samplers=("palette",), inputs=_PART_INPUTS,
                  varyings=(("smooth", "VEC4", "color"),))


def depth_shader() -> Any:
    """A part's depth alone (its position, no colour to interpolate: cheaper for llvmpipe to set up)."""
    return _build("depth", _DEPTH_VERTEX, _DEPTH_FRAGMENT, constants=(("MAT4", "mvp"),),
                  inputs=(("VEC3", "pos"),))


def resolve_shader(factor: int, edges: bool = False, glass: bool = False) -> Any:
    """The resolve shader for one supersampling factor (compiled once per process and variant);
    `edges`: factor 1, mixing the edges' pixels as the edge buffer says (:mod:`.edge_aa`); `glass`:
    a glass layer put over the image first (:mod:`.glass_layers`)."""
    samplers = ("image", "edges")[:1 + edges] + ("glass",) * glass
    return _build(("resolve", factor, edges, glass), _RESOLVE_VERTEX, _RESOLVE_FRAGMENT,
                  defines={"FACTOR": factor, "EDGES": int(edges), "GLASS": int(glass)},
                  constants=(("INT", "out_height"),), samplers=samplers, inputs=(("VEC2", "pos"),))


def edge_shader() -> Any:
    """The edges of :mod:`brainpainter_blender.edge_aa` as lines: which neighbour, how much of it."""
    return _build("edge", _EDGE_VERTEX, _EDGE_FRAGMENT,
                  constants=(("MAT4", "mvp"), ("VEC2", "viewport"), ("FLOAT", "bias")),
                  inputs=(("VEC3", "pos"), ("VEC3", "other")),
                  varyings=(("no_perspective", "VEC2", "anchor"), ("flat", "VEC2", "dir")))


def box_shader(step: str, factor: int = 1) -> Any:
    """A pass over the tracts' box: ``fill`` and ``colour`` (output-sized), ``over`` (supersampled)."""
    samplers, source = {"fill": (("slots",), _FILL_FRAGMENT),
                        "colour": (("shade", "slots", "palette"), _COLOUR_FRAGMENT),
                        "over": (("layer",), _OVER_FRAGMENT)}[step]
    return _build(("box", step, factor), _BOX_VERTEX, source,
                  defines={"FACTOR": factor, "PALETTE_WIDTH": PALETTE_WIDTH},
                  constants=(("VEC4", "box"),), samplers=samplers, inputs=(("VEC2", "pos"),))


def draw_box(step: str, box: tuple[float, float, float, float], samplers: dict[str, Any],
             factor: int = 1) -> None:
    """Run :func:`box_shader` `step` over `box` (x0, y0, x1, y1, normalised device coordinates) in the
    bound framebuffer, its samplers bound to `samplers` (name: texture)."""
    import gpu

    shader = box_shader(step, factor)
    shader.bind()
    for name, texture in samplers.items():
        shader.uniform_sampler(name, texture)
    shader.uniform_float("box", box)
    gpu.state.depth_test_set("NONE")
    gpu.state.face_culling_set("NONE")
    square = _shaders.get("square")
    if square is None:  # two triangles over the unit square, kept with the shaders
        from gpu_extras.batch import batch_for_shader

        corners = [(0, 0), (1, 0), (1, 1), (0, 0), (1, 1), (0, 1)]
        square = _keep("square", batch_for_shader(shader, "TRIS", {"pos": corners}))
    square.draw(shader)


def line_shader() -> Any:
    """Tract centrelines as anti-aliased, lit lines: their light and their slots (compiled once)."""
    return _build("line", _LINE_VERTEX, _LINE_FRAGMENT,
                  constants=(("MAT4", "mvp"), ("VEC2", "viewport"), ("FLOAT", "half_width"),
                             ("VEC3", "key_dir"), ("VEC3", "fill_dir"), ("FLOAT", "ambient"),
                             ("FLOAT", "key"), ("FLOAT", "fill"), ("FLOAT", "contrast")),
                  inputs=(("VEC3", "pos"), ("VEC3", "tang"), ("FLOAT", "pal"), ("FLOAT", "cap"),
                          ("FLOAT", "odd")),
                  varyings=tuple(("no_perspective", kind, name) for kind, name in (
                      ("VEC2", "centre"), ("VEC2", "dir"), ("FLOAT", "even_slot"), ("FLOAT", "odd_slot"),
                      ("FLOAT", "towards_odd"))),
                  outputs=(("VEC4", "lit"), ("VEC4", "slot")))


def _build(key: Any, vertex: str, fragment: str, *, defines: dict[str, int] | None = None,
           constants: tuple[tuple[str, str], ...] = (), samplers: tuple[str, ...] = (),
           inputs: tuple[tuple[str, str], ...] = (), varyings: tuple[tuple[str, str, str], ...] = (),
           outputs: tuple[tuple[str, str], ...] = (("VEC4", "fragColor"),)) -> Any:
    """The shader `key`, compiled on first use (in a GPU context) and kept for the process.

    Parameters
    ----------
    key : hashable
        Its name in the cache (``str`` for those with `varyings`: it names their interface).
    vertex, fragment : str
        GLSL sources (``main`` only: Blender declares what the create-info lists).
    defines : dict of str to int, optional
        Compile-time constants.
    constants, inputs, outputs : tuple of (type, name)
        Push constants; vertex attributes and fragment outputs, in their locations' order.
    samplers : tuple of str
        2-D float samplers, in their slots' order.
    varyings : tuple of (interpolation, type, name)
        Vertex-to-fragment values; interpolation ``smooth`` or ``no_perspective``.
    """
    if key in _shaders:
        return _shaders[key]
    import gpu

    info = gpu.types.GPUShaderCreateInfo()
    for name, value in (defines or {}).items():
        info.define(name, str(int(value)))
    for kind, name in constants:
        info.push_constant(kind, name)
    for slot, name in enumerate(samplers):
        info.sampler(slot, "FLOAT_2D", name)
    for location, (kind, name) in enumerate(inputs):
        info.vertex_in(location, kind, name)
    extra = ()
    if varyings:
        iface = gpu.types.GPUStageInterfaceInfo(f"brainpainter_{key}")
        for interpolation, kind, name in varyings:
            getattr(iface, interpolation)(kind, name)
        info.vertex_out(iface)
        extra = (iface,)  # kept: the compiled shader refers to it
    for location, (kind, name) in enumerate(outputs):
        info.fragment_out(location, kind, name)
    info.vertex_source(vertex)
    info.fragment_source(fragment)
    return _keep(key, gpu.shader.create_from_info(info), *extra)


def _keep(key: Any, shader: Any, *extra: Any) -> Any:
    if not _shaders:
        # Drop them before Blender's own exit handler, which reports GPU blocks still held.
        atexit.register(_shaders.clear)
    _shaders[key] = shader
    for i, obj in enumerate(extra):
        _shaders[(key, i)] = obj
    return shader
