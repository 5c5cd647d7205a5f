"""Map values to colours: BrainPainter gradients and matplotlib colour maps.

The original BrainPainter rule: with a gradient of N control colours, a value
v in [0, N-1] gets ``(1 - t) * C[floor(v)] + t * C[floor(v) + 1]`` with
``t = v - floor(v)``; values outside [0, N-1] clamp to the end colours.
Interpolation is on the sRGB components, exactly as the original.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from brainpainter.color.rgb import ColorLike, to_hex, to_rgb
from brainpainter.errors import BrainPainterError, nearest

DEFAULT_GRADIENT = ("white", "yellow", "orange", "red")
DEFAULT_NAN_COLOR = "#8c8c8c"
DEFAULT_MISSING_COLOR = "#d0d0d0"


@dataclass(frozen=True)
class ColourScale:
    """A value-to-colour mapping fixed for a whole run (all rows, all frames).

    Attributes
    ----------
    colors : ndarray of float, shape (N, 3)
        Control colours (sRGB, 0-1). For a matplotlib colour map, 256 samples.
    vmin, vmax : float
        Values mapped to the first and last control colour.
    center : float or None
        Diverging mode: this value maps to the middle of the colours; each
        side is scaled on its own (``vmin..center`` and ``center..vmax``).
    nan_color, missing_color : tuple of float, shape (3,)
        Colour of NaN / empty cells, and of regions absent from the input.
    name : str
        The gradient (``"white,yellow,orange,red"``) or colour-map name.
    """

    colors: np.ndarray
    vmin: float
    vmax: float
    center: float | None = None
    nan_color: tuple[float, float, float] = field(default_factory=lambda: to_rgb(DEFAULT_NAN_COLOR))
    missing_color: tuple[float, float, float] = field(
        default_factory=lambda: to_rgb(DEFAULT_MISSING_COLOR)
    )
    name: str = ""

    def __post_init__(self) -> None:
        for what, v in (("vmin", self.vmin), ("vmax", self.vmax), ("center", self.center)):
            if v is not None and not np.isfinite(v):
                raise BrainPainterError(f"{what} must be a finite number; {v!r} was given.")
        if not self.vmax > self.vmin:
            raise BrainPainterError(
                f"vmax must be greater than vmin; vmin={self.vmin:g} and vmax={self.vmax:g} were given."
            )
        if self.center is not None and not self.vmin < self.center < self.vmax:
            raise BrainPainterError(
                f"center must lie strictly between vmin and vmax; center={self.center:g}, "
                f"vmin={self.vmin:g}, vmax={self.vmax:g} were given."
            )

    @property
    def n_colors(self) -> int:
        return len(self.colors)

    def position(self, values: np.ndarray) -> np.ndarray:
        """Fractional position along the control colours, in [0, N-1].

        Parameters
        ----------
        values : array_like of float, shape (n,)

        Returns
        -------
        ndarray of float, shape (n,); NaN stays NaN.
        """
        v = np.asarray(values, dtype=float)
        top = self.n_colors - 1
        if self.center is None:
            t = (v - self.vmin) / (self.vmax - self.vmin)
        else:
            c = self.center
            t = np.where(v < c, 0.5 * (v - self.vmin) / (c - self.vmin),
                         0.5 + 0.5 * (v - c) / (self.vmax - c))
        return np.clip(t, 0.0, 1.0) * top

    def __call__(self, values: np.ndarray | Sequence[float] | float) -> np.ndarray:
        """Colours for values.

        Parameters
        ----------
        values : array_like of float, shape (n,) or scalar

        Returns
        -------
        ndarray of float, shape (n, 3) (or (3,) for a scalar), sRGB in 0-1.
        NaN values get ``nan_color``.
        """
        v = np.asarray(values, dtype=float)
        scalar = v.ndim == 0
        v = np.atleast_1d(v)
        pos = self.position(v)
        nan = ~np.isfinite(pos)
        pos = np.where(nan, 0.0, pos)
        if self.n_colors == 1:
            out = np.repeat(self.colors[:1], len(pos), axis=0)
        else:
            lo = np.minimum(np.floor(pos).astype(int), self.n_colors - 2)
            t = (pos - lo)[:, None]
            out = (1.0 - t) * self.colors[lo] + t * self.colors[lo + 1]
        out[nan] = self.nan_color
        return out[0] if scalar else out

    def ticks(self) -> np.ndarray:
        """Values at the control colours of a gradient (or 5 ticks for a colour map)."""
        n = self.n_colors if self.n_colors <= 12 else 5
        pos = np.linspace(0.0, 1.0, n)
        if self.center is None:
            return self.vmin + pos * (self.vmax - self.vmin)
        c = self.center
        return np.where(pos < 0.5, self.vmin + 2 * pos * (c - self.vmin), c + (2 * pos - 1) * (self.vmax - c))

    def to_dict(self) -> dict:
        """JSON-ready settings (for manifests and PNG metadata)."""
        return {
            "name": self.name,
            "colors": [to_hex(c) for c in self.colors] if self.n_colors <= 32 else None,
            "vmin": self.vmin,
            "vmax": self.vmax,
            "center": self.center,
            "nan_color": to_hex(self.nan_color),
            "missing_color": to_hex(self.missing_color),
        }


def gradient_colors(gradient: Sequence[ColorLike] | str) -> np.ndarray:
    """Parse a gradient: a list of colours or a comma/space separated string.

    Returns
    -------
    ndarray of float, shape (N, 3)
    """
    if isinstance(gradient, str):
        items: list[ColorLike] = [g for g in gradient.replace(";", ",").split(",") if g.strip()]
        # "255 0 0, 0 0 255" style triples are not supported in one string: use hex or names.
    else:
        items = list(gradient)
    if len(items) < 2:
        raise BrainPainterError(
            f"a gradient needs at least 2 colours; {gradient!r} was given. "
            "Example: --gradient white,yellow,orange,red"
        )
    return np.array([to_rgb(c) for c in items], dtype=float)


def cmap_colors(name: str, n: int = 256) -> np.ndarray:
    """Sample a matplotlib colour map by name.

    Returns
    -------
    ndarray of float, shape (n, 3)
    """
    import matplotlib

    try:
        cmap = matplotlib.colormaps[name]
    except KeyError:
        allowed = sorted(matplotlib.colormaps)
        close = nearest(name, allowed)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise BrainPainterError(
            f"colour map {name!r} is not a matplotlib colour map (e.g. 'viridis', 'RdBu_r', "
            f"'magma'; see matplotlib.colormaps).{hint}"
        ) from None
    return np.asarray(cmap(np.linspace(0.0, 1.0, n)))[:, :3]


def make_scale(
    gradient: Sequence[ColorLike] | str | None = None,
    cmap: str | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    center: float | None = None,
    nan_color: ColorLike = DEFAULT_NAN_COLOR,
    missing_color: ColorLike = DEFAULT_MISSING_COLOR,
    data: np.ndarray | None = None,
) -> ColourScale:
    """Build the colour scale for a run.

    With a gradient of N colours and no vmin/vmax the original convention
    holds: values 0 .. N-1. With a colour map, vmin/vmax default to the
    finite range of `data` (symmetric about `center` in diverging mode).

    Parameters
    ----------
    gradient : list of colours or str, optional
        Control colours; the default is BrainPainter's white, yellow, orange, red.
    cmap : str, optional
        A matplotlib colour map name (exclusive with `gradient`).
    vmin, vmax, center : float, optional
    nan_color, missing_color : colour
    data : ndarray, optional
        All values of the run, for default limits.
    """
    if gradient is not None and cmap is not None:
        raise BrainPainterError(
            "give either a gradient or a colour map, not both; "
            f"gradient={gradient!r} and cmap={cmap!r} were given."
        )
    if cmap is not None:
        colors, name = cmap_colors(cmap), cmap
    else:
        colors = gradient_colors(gradient if gradient is not None else DEFAULT_GRADIENT)
        if gradient is None:
            gradient = DEFAULT_GRADIENT
        name = gradient if isinstance(gradient, str) else ",".join(str(g) for g in gradient)
    values = np.asarray(data if data is not None else [], dtype=float).ravel()
    finite = values[np.isfinite(values)]
    if cmap is None and vmin is None and vmax is None:
        lo, hi = (0.0, float(len(colors) - 1)) if center is None else (None, None)
    else:
        lo, hi = vmin, vmax
    if lo is None or hi is None:
        if center is not None and (lo is None and hi is None):
            half = float(np.max(np.abs(finite - center))) if finite.size else 1.0
            half = half or 1.0
            lo, hi = center - half, center + half
        else:
            dlo = float(finite.min()) if finite.size else 0.0
            dhi = float(finite.max()) if finite.size else 1.0
            lo = dlo if lo is None else lo
            hi = dhi if hi is None else hi
            if hi <= lo:
                hi = lo + 1.0
    return ColourScale(
        colors=colors,
        vmin=float(lo),
        vmax=float(hi),
        center=None if center is None else float(center),
        nan_color=to_rgb(nan_color),
        missing_color=to_rgb(missing_color),
        name=name,
    )
