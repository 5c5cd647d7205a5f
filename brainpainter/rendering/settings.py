"""Image settings shared by every image of a run: size, background, quality, shading, lighting.

:class:`RenderSettings` is the one definition of these options: its fields
carry the defaults and the help text that the CLI (``brainpainter.cli.options``)
and the web API (``brainpainter.web.options``) show, and it checks them once,
when it is made.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, TypedDict

from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.errors import BrainPainterError, choice_error, within

RGB = tuple[float, float, float]
QUALITIES = ("fast", "default", "high")
SHADINGS = ("default", "flat")
LIGHTINGS = ("studio", "soft", "flat-studio", "sulc")
#: Lighting presets that darken sulci (they need the cortex's sulcal depth).
SULC_LIGHTINGS = ("flat-studio", "sulc")
#: Width of region borders drawn by ``--outline`` when ``--outline-width`` is not given, and the most.
DEFAULT_OUTLINE_WIDTH, MAX_OUTLINE_WIDTH = 1.5, 20.0
#: How a line layer (the outline, the contour) is drawn: a solid line, or dashes 3 mm long 2 mm apart on
#: the surface (:func:`brainpainter.rendering.borders.dashed`).
LINE_STYLES = ("solid", "dashed")
#: How the cortex views (lateral, medial, dorsal, ...) draw the cortex: ``auto`` is ``glass`` when the
#: scene has white-matter tracts, else ``opaque``.
CORTEX_MODES = ("auto", "opaque", "glass", "hull", "hidden")
#: Smallest and largest width or height of one image, pixels.
MIN_PIXELS, MAX_PIXELS = 16, 8192


def parse_size(size: str) -> tuple[int, int]:
    """``"1200x900"`` -> ``(1200, 900)`` (the CLI's and the web API's ``size``)."""
    try:
        w, h = (int(x) for x in str(size).lower().replace("\u00d7", "x").split("x"))
    except ValueError:
        raise BrainPainterError(f"--size must be WIDTHxHEIGHT, e.g. 1200x900; {size!r} was given.") from None
    return w, h


class SettingsKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`RenderSettings` (``render(width=...)``, ...)."""

    width: int
    height: int
    background: ColorLike | None
    quality: str
    shading: str
    lighting: str
    glass_opacity: float
    outline_width: float
    outline_color: ColorLike
    outline_style: str
    contour_width: float
    contour_color: ColorLike | None
    contour_style: str
    cortex: str


def check_pixels(what: str, n: Any) -> int:
    """`n` as a whole number of pixels in 16..8192, or a one-line error naming `what`."""
    try:
        ok = float(n) == int(n) and MIN_PIXELS <= int(n) <= MAX_PIXELS
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise BrainPainterError(f"{what} must be between {MIN_PIXELS} and {MAX_PIXELS} pixels (a whole "
                                f"number); {n!r} was given.")
    return int(n)


@dataclass(frozen=True)
class RenderSettings:
    """Image settings shared by every image of a run; checked when made.

    Attributes
    ----------
    width, height : int
        Pixels, 16 to 8192; default 1200 x 900 as the original BrainPainter.
    background : colour or None
        Stored as sRGB 0-1, tuple of float, shape (3,); ``None`` renders a
        transparent background.
    quality : {"fast", "default", "high"}
        ``fast``: no anti-aliasing; ``default``: region borders and silhouettes
        anti-aliased from the geometry; ``high``: path tracing (Cycles), or 3x3
        supersampling for flat shading.
    shading : {"default", "flat"}
        ``flat`` draws exact, unlit colours.
    lighting : {"studio", "soft", "flat-studio", "sulc"}
        Lighting preset for default shading: ``studio`` key + fill + ambient
        light that follow the camera; ``soft`` more ambient, flatter; ``sulc``
        studio plus a slight darkening of sulci (sulcal depth);
        ``flat-studio`` unlit colours darkened in sulci. On a map's cortex the lit presets
        darken less (less occlusion and contrast), so its colours read as its values.
    glass_opacity : float
        Opacity of the glass brain, 0-1.
    outline_width : float
        Width in pixels of the region borders drawn over the cortex as lines, the same in
        every image size (``--outline``); 0: none.
    outline_color : colour
        Their colour, stored as sRGB 0-1 (default black; white reads well on dark maps).
    outline_style, contour_style : {"solid", "dashed"}
        How the region borders and the contour's iso-lines are drawn (:data:`LINE_STYLES`).
    contour_width : float
        Width in pixels of the contour's iso-lines (``--contour``); 0: ``outline_width``.
    contour_color : colour, optional
        Their colour; None: ``outline_color``.
    cortex : {"auto", "opaque", "glass", "hull", "hidden"}
        How the cortex views draw the cortex: ``opaque``; ``glass``, transparent
        in its colours (``glass_opacity``) with the white-matter tracts of the
        view's hemispheres inside; ``hull``, the smooth glass brain of the subcortical
        views (the template's glass hulls) instead of the cortex; ``hidden``, the tracts alone; ``auto``
        (default): ``glass`` when the scene has tracts, else ``opaque`` (a run whose
        cortex carries values draws it ``opaque`` with tracts too:
        :func:`brainpainter.rendering.composition.cortex_for`).
    """

    width: int = field(default=1200, metadata={"help": "Image width, pixels."})
    height: int = field(default=900, metadata={"help": "Image height, pixels."})
    background: RGB | None = field(default=(1.0, 1.0, 1.0), metadata={
        "help": "Background colour.", "cli_default": "white"})
    quality: str = field(default="default", metadata={"choices": QUALITIES, "help": (
        "fast: no anti-aliasing; default: anti-aliased edges; high: path tracing (Cycles), slow.")})
    shading: str = field(default="default", metadata={"choices": SHADINGS, "help": (
        "flat: exact, unlit colours (for measuring colours in the image).")})
    lighting: str = field(default="studio", metadata={
        "choices": LIGHTINGS, "help": "sulc: studio light with sulci darkened slightly (sulcal depth)."})
    glass_opacity: float = field(default=0.12, metadata={"help": "Opacity of the glass brain, 0-1."})
    outline_width: float = field(default=0.0, metadata={"help": (
        "Draw the atlas's region borders over the cortex as lines this many pixels wide, at any image "
        f"size (0: none; --outline ATLAS alone draws them {DEFAULT_OUTLINE_WIDTH:g} px wide).")})
    outline_color: RGB = field(default=(0.0, 0.0, 0.0), metadata={
        "help": "Colour of the region borders (--outline), e.g. black or white.", "cli_default": "black"})
    outline_style: str = field(default="solid", metadata={
        "choices": LINE_STYLES, "help": "Line of the region borders (--outline): solid or dashed."})
    contour_width: float = field(default=0.0, metadata={"help": (
        "Width in pixels of the contour's lines (--contour); 0: the --outline-width.")})
    contour_color: RGB | None = field(default=None, metadata={
        "help": "Colour of the contour's lines (--contour), e.g. red; default: the --outline-color."})
    contour_style: str = field(default="solid", metadata={
        "choices": LINE_STYLES, "help": "Line of the contour (--contour): solid or dashed."})
    cortex: str = field(default="auto", metadata={"choices": CORTEX_MODES, "help": (
        "How cortex views (lateral, medial, dorsal, ...) draw the cortex: glass shows the --tracts inside "
        "a transparent cortex in its colours, hull the smooth glass brain of the subcortical views instead, "
        "hidden the tracts alone; auto: glass with --tracts, hull with a connectome, opaque where the "
        "cortex carries values (a map, cortical region values; glass with a connectome) or with neither.")})

    def __post_init__(self) -> None:
        for name, allowed in (("quality", QUALITIES), ("shading", SHADINGS), ("lighting", LIGHTINGS),
                              ("cortex", CORTEX_MODES), ("outline_style", LINE_STYLES),
                              ("contour_style", LINE_STYLES)):
            if getattr(self, name) not in allowed:
                raise choice_error(name, getattr(self, name), allowed)
        object.__setattr__(self, "width", check_pixels("width", self.width))
        object.__setattr__(self, "height", check_pixels("height", self.height))
        if not within(self.glass_opacity, 0.0, 1.0):
            raise BrainPainterError(f"glass opacity must be in [0, 1]; {self.glass_opacity} was given.")
        object.__setattr__(self, "glass_opacity", float(self.glass_opacity))
        for name in ("outline_width", "contour_width"):
            try:
                width = float(getattr(self, name))
            except (TypeError, ValueError):
                width = float("nan")
            if not 0.0 <= width <= MAX_OUTLINE_WIDTH:
                what = name.split("_")[0]
                raise BrainPainterError(f"{what} width must be 0 (none) to {MAX_OUTLINE_WIDTH:g} pixels; "
                                        f"{getattr(self, name)!r} was given.")
            object.__setattr__(self, name, width)
        object.__setattr__(self, "outline_color", to_rgb(self.outline_color))
        if self.contour_color is not None:
            object.__setattr__(self, "contour_color", to_rgb(self.contour_color))
        if self.background is not None:
            object.__setattr__(self, "background", to_rgb(self.background))

    @property
    def size(self) -> str:
        """``"WIDTHxHEIGHT"``."""
        return f"{self.width}x{self.height}"

    def to_dict(self) -> dict[str, object]:
        """JSON-ready settings (for manifests and PNG metadata)."""
        return {
            "width": self.width, "height": self.height,
            "background": None if self.background is None else list(self.background),
            "quality": self.quality, "shading": self.shading,
            "lighting": self.lighting, "glass_opacity": self.glass_opacity, "cortex": self.cortex,
            **({"outline_width": self.outline_width, "outline_color": list(self.outline_color)}
               if self.outline_width else {}),
            **{name: value for name, value in (
                ("outline_style", self.outline_style), ("contour_width", self.contour_width or None),
                ("contour_color", None if self.contour_color is None else list(self.contour_color)),
                ("contour_style", self.contour_style)) if value not in (None, "solid")},
        }

    def line(self, kind: str) -> tuple[RGB, float, str]:
        """The colour (sRGB), width (pixels) and style of line layer `kind` (``outline``, ``contour``): the
        contour's own where given, else the outline's."""
        if kind == "contour":
            return (self.contour_color or self.outline_color, self.contour_width or self.outline_width,
                    self.contour_style)
        return self.outline_color, self.outline_width, self.outline_style


def outlined(settings: RenderSettings, outline: str | None) -> RenderSettings:
    """`settings` drawing region borders when ``--outline ATLAS`` is given: its ``--outline-width``,
    or :data:`DEFAULT_OUTLINE_WIDTH` pixels."""
    from dataclasses import replace

    if outline is None or settings.outline_width > 0:
        return settings
    return replace(settings, outline_width=DEFAULT_OUTLINE_WIDTH)


def with_aspect(settings: RenderSettings, aspect: float) -> RenderSettings:
    """`settings` with width / height = `aspect` and about as many pixels (even numbers).

    A size the user did not give follows the atlas's shape (:attr:`Atlas.image_aspect`): the
    mouse brain, 0.8 as wide as long, fills 56 % of a 1200 x 900 image seen from above but
    75 % of a 1040 x 1040 one, while its side views still fill the width.
    """
    from dataclasses import replace

    pixels = settings.width * settings.height
    width = max(16, 2 * round((pixels * aspect) ** 0.5 / 2))
    height = max(16, 2 * round((pixels / aspect) ** 0.5 / 2))
    return replace(settings, width=width, height=height)
