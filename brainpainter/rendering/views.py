"""Camera presets: BrainPainter's views and more, in anatomical terms.

Coordinates are RAS (x right, y anterior, z superior). ``azimuth`` is the
camera's direction from the brain centre in the horizontal plane, in degrees
counter-clockwise from +x seen from above: 0 = from the right, 90 = from the
front, 180 = from the left, 270 = from behind. ``elevation`` is the angle
above the horizontal plane: 90 = from above, -90 = from below. The image's
up is superior, except straight from above or below where it is anterior.

The flat views (``flat-left``, ``flat-right``, ``flat``) look straight down
at HCP's flat maps (:mod:`brainpainter.maps.flat`), which lie in the plane
z = 0, the left hemisphere's left of the right one's.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from brainpainter.errors import BrainPainterError, nearest
from brainpainter.rendering.clip import ClipPlane


@dataclass(frozen=True)
class View:
    """What to draw and from where.

    Attributes
    ----------
    name : str
    content : {"cortex", "subcortical", "flat"}
        ``cortex`` draws the cortical hemispheres in `hemis`; ``subcortical``
        draws all subcortical structures plus the cortex of `glass` as glass;
        ``flat`` the flat maps of `hemis` (a 2-D view: no subcortical parts).
    hemis : tuple of {"lh", "rh"}
        Cortical hemispheres drawn opaque.
    glass : tuple of {"lh", "rh"}
        Hemispheres drawn as a transparent glass brain.
    azimuth, elevation : float
        Camera direction in degrees (see module docstring).
    zoom : float
        > 1 moves the camera closer.
    clip : tuple of ClipPlane
        Cutaway planes (:mod:`brainpainter.rendering.clip`): the cortex and the glass on their side
        are removed, and a cortex view also draws what lies inside (structures, blobs, tracts, nodes).
    """

    name: str
    content: str
    hemis: tuple[str, ...]
    azimuth: float
    elevation: float
    zoom: float = 1.0
    glass: tuple[str, ...] = ()
    clip: tuple[ClipPlane, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        out = {
            "name": self.name, "content": self.content, "hemis": list(self.hemis),
            "glass": list(self.glass), "azimuth": self.azimuth,
            "elevation": self.elevation, "zoom": self.zoom,
        }
        if self.clip:
            out["clip"] = [str(p) for p in self.clip]
        return out


_BOTH = ("lh", "rh")
PRESETS: dict[str, View] = {
    v.name: v
    for v in (
        View("lateral-left", "cortex", ("lh",), 180.0, 0.0),
        View("medial-left", "cortex", ("lh",), 0.0, 0.0),
        View("lateral-right", "cortex", ("rh",), 0.0, 0.0),
        View("medial-right", "cortex", ("rh",), 180.0, 0.0),
        View("dorsal", "cortex", _BOTH, 0.0, 90.0),
        View("ventral", "cortex", _BOTH, 0.0, -90.0),
        View("anterior", "cortex", _BOTH, 90.0, 0.0),
        View("posterior", "cortex", _BOTH, 270.0, 0.0),
        View("subcortical", "subcortical", (), 160.0, 20.0, glass=("rh",)),
        View("subcortical-left", "subcortical", (), 180.0, 0.0, glass=("rh",)),
        View("subcortical-dorsal", "subcortical", (), 0.0, 90.0, glass=_BOTH),
        View("subcortical-ventral", "subcortical", (), 0.0, -90.0, glass=_BOTH),
        View("flat-left", "flat", ("lh",), 0.0, 90.0),
        View("flat-right", "flat", ("rh",), 0.0, 90.0),
        View("flat", "flat", _BOTH, 0.0, 90.0),
    )
}
DEFAULT_VIEWS = ("lateral-left", "medial-left", "subcortical")
#: Views that cut the cortex open (a clip with a camera); not among ``all``.
CUTAWAYS: dict[str, View] = {
    v.name: v
    for v in (
        View("cutaway-left", "cortex", _BOTH, 180.0, 0.0, clip=(ClipPlane("x", "<", 0.0),)),
        View("cutaway-right", "cortex", _BOTH, 0.0, 0.0, clip=(ClipPlane("x", ">", 0.0),)),
        View("cutaway-dorsal", "cortex", _BOTH, 0.0, 90.0, clip=(ClipPlane("z", ">", 10.0),)),
        View("cutaway-anterior", "cortex", _BOTH, 90.0, 0.0, clip=(ClipPlane("y", ">", 0.0),)),
        View("cutaway-corner", "cortex", _BOTH, 135.0, 30.0,
             clip=(ClipPlane("x", "<", 0.0), ClipPlane("z", ">", 10.0))),
    )
}

# The original BrainPainter's names, and common synonyms.
ALIASES: dict[str, str] = {
    "cortical-outer-left-hemisphere": "lateral-left",
    "cortical-inner-left-hemisphere": "medial-left",
    "cortical-outer-right-hemisphere": "lateral-right",
    "cortical-inner-right-hemisphere": "medial-right",
    "cortical-outer": "lateral-left",
    "cortical-inner": "medial-left",
    "top": "dorsal",
    "bottom": "ventral",
    "front": "anterior",
    "back": "posterior",
    "superior": "dorsal",
    "inferior": "ventral",
    "subcortical-top": "subcortical-dorsal",
    "left-lateral": "lateral-left",
    "left-medial": "medial-left",
    "right-lateral": "lateral-right",
    "right-medial": "medial-right",
    "left-flat": "flat-left",
    "right-flat": "flat-right",
    "flatmap": "flat",
}


def get_view(name: str) -> View:
    """A preset view by name or alias (case-insensitive)."""
    key = str(name).strip().lower()
    key = ALIASES.get(key, key)
    if key in CUTAWAYS:
        return CUTAWAYS[key]
    if key not in PRESETS:
        # current names first (in preset order), the original BrainPainter's names after them
        close = nearest(str(name), [*PRESETS, *CUTAWAYS, *ALIASES])
        hint = f" Did you mean {ALIASES.get(close[0], close[0])!r}?" if close else ""
        raise BrainPainterError(
            f"view must be one of {[*PRESETS, *CUTAWAYS, 'all', 'camera:AZ:EL[:ZOOM]']}; {name!r} was "
            f"given.{hint} "
            f"The original BrainPainter's names work too: {[*list(ALIASES)[:6], '...']}."
        )
    return PRESETS[key]


def camera_view(azimuth: float, elevation: float, zoom: float = 1.0,
                hemis: tuple[str, ...] = _BOTH, name: str | None = None) -> View:
    """A free camera on the cortex of `hemis`."""
    import math

    if not math.isfinite(float(azimuth)):
        raise BrainPainterError(f"azimuth must be a finite number of degrees; {azimuth} was given.")
    if not -90.0 <= elevation <= 90.0 or not 0 < zoom <= 100:
        raise BrainPainterError(
            f"elevation must be in [-90, 90] and zoom in (0, 100]; elevation={elevation}, zoom={zoom} were "
            "given."
        )
    name = name or f"az{azimuth:g}-el{elevation:g}" + (f"-zoom{zoom:g}" if zoom != 1 else "")
    return View(name, "cortex", tuple(hemis), float(azimuth) % 360.0, float(elevation), float(zoom))


def parse_views(spec: str | list[str] | tuple[str, ...] | None) -> list[View]:
    """Parse ``"lateral-left,medial-left"`` or a list; ``"all"`` gives every preset.

    A free camera is written ``camera:AZ:EL[:ZOOM]``.
    """
    if spec is None:
        return [PRESETS[v] for v in DEFAULT_VIEWS]
    items = spec.split(",") if isinstance(spec, str) else list(spec)
    out: list[View] = []
    for item in (i.strip() for i in items):
        if not item:
            continue
        if item.lower() == "all":
            out.extend(PRESETS.values())
        elif item.lower().startswith("camera:"):
            parts = item.split(":")[1:]
            try:
                nums = [float(p) for p in parts]
                if len(nums) not in (2, 3):
                    raise ValueError
            except ValueError:
                raise BrainPainterError(
                    f"free camera {item!r} must be camera:AZIMUTH:ELEVATION[:ZOOM] in degrees, "
                    "e.g. camera:135:30:1.2"
                ) from None
            out.append(camera_view(nums[0], nums[1], nums[2] if len(nums) > 2 else 1.0))
        else:
            out.append(get_view(item))
    if not out:
        raise BrainPainterError(f"no view was given in {spec!r}; e.g. --views lateral-left,medial-left")
    seen: dict[str, View] = {}
    for v in out:
        seen.setdefault(v.name, v)
    return list(seen.values())


def with_zoom(view: View, zoom: float) -> View:
    return replace(view, zoom=zoom)


def with_clip(views: list[View], planes: tuple[ClipPlane, ...]) -> list[View]:
    """`views` each cut by `planes` too (``--clip``), the view's own planes first; none: as given."""
    if not planes:
        return views
    return [replace(v, clip=tuple(dict.fromkeys(v.clip + planes))) for v in views]


class ImagesByView(dict[tuple[str, str], Any]):
    """``(image name, view name) -> image``, also found under the view as the user wrote it.

    A free camera is stored under its canonical name (``az90-el0``, also in
    file names) and found as written: ``images[("1", "camera:90:0")]``, as
    are other spellings of a view (``"Lateral-Left"``) and a row number given
    as an int (``images[(1, "lateral-left")]``).
    """

    def __missing__(self, key: tuple[Any, Any]) -> Any:
        if isinstance(key, tuple) and len(key) == 2 and isinstance(key[1], str):
            image, view = key
            try:
                names = [v.name for v in parse_views(view)]
            except BrainPainterError:
                names = []
            other = (str(image), names[0]) if len(names) == 1 else None
            if other is not None and other != key and dict.__contains__(self, other):
                return dict.__getitem__(self, other)
        raise KeyError(key)

    def __contains__(self, key: object) -> bool:
        try:
            self[key]  # type: ignore[index]
        except KeyError:
            return False
        return True

    def get(self, key: Any, default: Any = None) -> Any:
        try:
            return self[key]
        except KeyError:
            return default
