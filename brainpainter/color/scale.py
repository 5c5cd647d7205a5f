"""Map values to colours: BrainPainter gradients and matplotlib colour maps.

The original BrainPainter rule: with a gradient of N control colours, a value
v in [0, N-1] gets ``(1 - t) * C[floor(v)] + t * C[floor(v) + 1]`` with
``t = v - floor(v)``; values outside [0, N-1] clamp to the end colours.
Interpolation is on the sRGB components, exactly as the original.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict, Unpack

if TYPE_CHECKING:
    from numpy.typing import NDArray

from brainpainter.color.rgb import ColorLike, to_hex, to_rgb
from brainpainter.errors import BrainPainterError, nearest

DEFAULT_GRADIENT = ("white", "yellow", "orange", "red")
DEFAULT_NAN_COLOR = "#8c8c8c"
DEFAULT_MISSING_COLOR = "#d0d0d0"


def fraction(values: NDArray[Any], lo: float, hi: float) -> NDArray[Any]:
    """``(values - lo) / (hi - lo)`` without overflow for any finite numbers (``±1e308``, subnormals).

    Parameters
    ----------
    values : ndarray of float, shape (n,)
    lo, hi : float
        Finite, ``lo < hi``.

    Returns
    -------
    ndarray of float, shape (n,): finite for finite values (possibly far outside [0, 1], never NaN),
    NaN for NaN.
    """
    import numpy as np

    v = np.asarray(values, dtype=float)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore", under="ignore"):
        if np.isfinite(hi - lo):
            t = (v - lo) / (hi - lo)  # exact for subnormal ranges; far outside the range -> +-inf
        else:  # the span itself overflows: halve everything first
            t = (v * 0.5 - lo * 0.5) / (hi * 0.5 - lo * 0.5)
    return np.where(np.isnan(v), np.nan, np.clip(t, -1e300, 1e300))


def between(lo: float, hi: float, t: NDArray[Any] | float) -> NDArray[Any]:
    """``lo + t * (hi - lo)`` for ``t`` in [0, 1], without overflow for any finite `lo`, `hi`."""
    import numpy as np

    t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0)
    with np.errstate(under="ignore"):
        return np.asarray(lo * (1.0 - t) + hi * t)


#: The largest finite float: limits are kept within +-BIGGEST.
BIGGEST = 1.7976931348623157e308  # float(np.finfo(float).max), without importing numpy


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
    threshold : float or None
        A map's ``--threshold``: values with ``|v|`` below it are not coloured
        (the colour bar greys that band out).
    categories : tuple of (str, (r, g, b))
        A label map's categories in their own colours: the colour bar becomes a key of
        these (one block and name each) instead of a gradient of values.
    chosen : str
        Why an automatic scale is what it is (a map's ``"values >= 0"``); empty when given.
    """

    colors: NDArray[Any]
    vmin: float
    vmax: float
    center: float | None = None
    nan_color: tuple[float, float, float] = field(default_factory=lambda: to_rgb(DEFAULT_NAN_COLOR))
    missing_color: tuple[float, float, float] = field(
        default_factory=lambda: to_rgb(DEFAULT_MISSING_COLOR)
    )
    name: str = ""
    threshold: float | None = None
    categories: tuple[tuple[str, tuple[float, float, float]], ...] = ()
    chosen: str = ""

    def __repr__(self) -> str:
        """One short line (the control colours are many)."""
        center = "" if self.center is None else f", center={self.center:g}"
        return f"<ColourScale {self.name or 'custom'!r} {self.vmin:g}..{self.vmax:g}{center}>"

    def __post_init__(self) -> None:
        import numpy as np
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

    def position(self, values: NDArray[Any]) -> NDArray[Any]:
        """Fractional position along the control colours, in [0, N-1].

        Parameters
        ----------
        values : array_like of float, shape (n,)

        Returns
        -------
        ndarray of float, shape (n,); NaN stays NaN.
        """
        import numpy as np
        v = np.asarray(values, dtype=float)
        top = self.n_colors - 1
        if self.center is None:
            t = fraction(v, self.vmin, self.vmax)
        else:
            c = self.center
            t = np.where(v < c, 0.5 * fraction(v, self.vmin, c), 0.5 + 0.5 * fraction(v, c, self.vmax))
        return np.clip(t, 0.0, 1.0) * top

    def __call__(self, values: NDArray[Any] | Sequence[float] | float) -> NDArray[Any]:
        """Colours for values.

        Parameters
        ----------
        values : array_like of float, shape (n,) or scalar

        Returns
        -------
        ndarray of float, shape (n, 3) (or (3,) for a scalar), sRGB in 0-1.
        NaN values get ``nan_color``.
        """
        import numpy as np
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

    def describe(self) -> str:
        """One line: the colour map, its range and why, e.g. ``viridis 0-4.7 (values >= 0)``."""
        joint = " to " if self.vmin < 0 else "-"
        why = f" ({self.chosen})" if self.chosen else ""
        return f"{self.name or 'custom'} {self.vmin:.3g}{joint}{self.vmax:.3g}{why}"

    def ticks(self) -> NDArray[Any]:
        """Default colour-bar ticks: round numbers inside ``[vmin, vmax]`` (and `center`).

        A gradient's control colours are its ticks where they fall on round numbers (0, 1, 2, 3;
        0, 25, 50); otherwise, and for a colour map, 4 to 7 round values (1.5, 2, 2.5; 0, 50,
        100) from matplotlib's :class:`~matplotlib.ticker.MaxNLocator`. The ends are ticks
        only where they are round; the bar itself always runs from vmin to vmax.

        Returns
        -------
        ndarray of float, shape (n_ticks,), increasing, within ``[vmin, vmax]``.
        """
        import numpy as np
        controls = self._control_values()
        if self.n_colors <= 12 and round_steps(controls):
            return controls
        nice = nice_ticks(self.vmin, self.vmax)
        if nice is None:  # no round numbers to show (ranges near the float limits): 5 even steps
            steps: NDArray[Any] = np.unique(self._values_at(np.linspace(0.0, 1.0, 5)))
            return steps
        step = float(nice[1] - nice[0])
        if self.center is not None and not (np.abs(nice - self.center) <= 1e-9 * step).any():
            nice = np.sort(np.append(nice[np.abs(nice - self.center) > 0.5 * step], self.center))
        return nice

    def _control_values(self) -> NDArray[Any]:
        """The values at the control colours (a colour map's 256 samples: at its 5 quarter points)."""
        import numpy as np
        return self._values_at(np.linspace(0.0, 1.0, self.n_colors if self.n_colors <= 12 else 5))

    def _values_at(self, pos: NDArray[Any]) -> NDArray[Any]:
        """The values at positions `pos` (0-1) along the colours (a diverging scale: each side on its own)."""
        import numpy as np
        if self.center is None:
            return between(self.vmin, self.vmax, pos)
        c = self.center
        return np.where(pos < 0.5, between(self.vmin, c, 2 * pos), between(c, self.vmax, 2 * pos - 1))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready settings (for manifests and PNG metadata)."""
        return {
            "name": self.name,
            "colors": [to_hex(c) for c in self.colors] if self.n_colors <= 32 else None,
            "vmin": self.vmin,
            "vmax": self.vmax,
            "center": self.center,
            "nan_color": to_hex(self.nan_color),
            "missing_color": to_hex(self.missing_color),
            **({} if self.threshold is None else {"threshold": self.threshold}),
            **({"categories": {n: to_hex(c) for n, c in self.categories}} if self.categories else {}),
        }


#: Round steps between ticks, times a power of ten (as matplotlib's MaxNLocator steps).
ROUND_STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)


def round_steps(values: NDArray[Any]) -> bool:
    """Whether `values` (shape (n,), increasing) are evenly spaced by a round step, each a multiple of it."""
    import math

    import numpy as np
    if len(values) < 2:
        return False
    with np.errstate(all="ignore"):
        steps = np.diff(values)
        step = float(steps[0])
        if not (math.isfinite(step) and step > 0 and np.allclose(steps, step, rtol=1e-9, atol=0)):
            return False
        mantissa = step / 10.0 ** math.floor(math.log10(step))
        multiples = np.asarray(values) / step
        return (any(math.isclose(mantissa, m, rel_tol=1e-9) for m in ROUND_STEPS)
                and bool(np.all(np.abs(multiples - np.round(multiples)) < 1e-6)))


def nice_ticks(vmin: float, vmax: float) -> NDArray[Any] | None:
    """4 to 7 round values in ``[vmin, vmax]`` (matplotlib's MaxNLocator), or None where there are none.

    Returns
    -------
    ndarray of float, shape (n,), or None (a range at the float limits, ``±1e308`` or subnormal).
    """
    import math
    import warnings

    import numpy as np
    from matplotlib.ticker import MaxNLocator

    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            found = MaxNLocator(nbins=6, steps=list(ROUND_STEPS), min_n_ticks=4).tick_values(vmin, vmax)
    except (ValueError, OverflowError, ZeroDivisionError):
        return None
    ticks: NDArray[Any] = np.asarray(found, dtype=float)
    if not np.isfinite(ticks).all() or len(ticks) < 2:
        return None
    with np.errstate(over="ignore"):
        step = float(ticks[1] - ticks[0])
    if not (math.isfinite(step) and step > 0):
        return None
    slack = 1e-9 * step
    inside = ticks[(ticks >= vmin - slack) & (ticks <= vmax + slack)]
    inside = np.where(np.abs(inside) < slack, 0.0, inside)  # 0, not 1e-17
    decimals = 1 - math.floor(math.log10(step))
    if decimals <= 15:  # 0.4, not 0.4000000000000001
        inside = np.round(inside, max(decimals, 0))
    return np.clip(inside, vmin, vmax) if len(inside) >= 2 else None


def gradient_colors(gradient: Sequence[ColorLike] | str) -> NDArray[Any]:
    """Parse a gradient: a list of colours or a comma/space separated string.

    Returns
    -------
    ndarray of float, shape (N, 3)
    """
    import numpy as np
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


def cmap_colors(name: str, n: int = 256) -> NDArray[Any]:
    """Sample a matplotlib colour map by name.

    Returns
    -------
    ndarray of float, shape (n, 3)
    """
    import matplotlib
    import numpy as np

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


class ScaleKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`ScaleOptions` (``render(cmap=...)``, :func:`make_scale`)."""

    gradient: Sequence[ColorLike] | str | None
    cmap: str | None
    vmin: float | None
    vmax: float | None
    center: float | None
    nan_color: ColorLike
    missing_color: ColorLike


@dataclass(frozen=True)
class ScaleOptions:
    """The colour-scale options of a run, checked once when made; :meth:`scale` builds the scale.

    With a gradient of N colours and no vmin/vmax the original convention
    holds: values 0 .. N-1. With a colour map, vmin/vmax default to the
    finite range of the data (symmetric about `center` in diverging mode).

    Attributes
    ----------
    gradient : list of colours or str, optional
        Control colours; the default is BrainPainter's white, yellow, orange, red.
    cmap : str, optional
        A matplotlib colour map name (exclusive with `gradient`).
    vmin, vmax, center : float, optional
        Values at the first, last and (diverging) middle colour.
    nan_color, missing_color : colour
        Colour of empty cells, and of regions with no column.
    """

    gradient: Sequence[ColorLike] | str | None = field(default=None, metadata={
        "help": "Control colours, e.g. white,yellow,orange,red (the default). Values 0..N-1."})
    cmap: str | None = field(default=None, metadata={
        "help": "A matplotlib colour map instead of a gradient, e.g. viridis."})
    vmin: float | None = field(default=None, metadata={"help": "Value at the first colour."})
    vmax: float | None = field(default=None, metadata={"help": "Value at the last colour."})
    center: float | None = field(default=None, metadata={"help": "Diverging: value at the middle colour."})
    nan_color: ColorLike = field(default=DEFAULT_NAN_COLOR, metadata={"help": "Colour of empty cells."})
    missing_color: ColorLike = field(default=DEFAULT_MISSING_COLOR, metadata={
        "help": "Colour of regions with no column."})
    _colors: NDArray[Any] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        gradient, cmap = self.gradient, self.cmap
        if gradient is not None and cmap is not None:
            raise BrainPainterError(
                "give either a gradient or a colour map, not both; "
                f"gradient={gradient!r} and cmap={cmap!r} were given."
            )
        colors = cmap_colors(cmap) if cmap is not None else gradient_colors(
            gradient if gradient is not None else DEFAULT_GRADIENT)
        object.__setattr__(self, "_colors", colors)
        self.scale()  # limits and colours: every error now, before any data is read

    @property
    def name(self) -> str:
        """The colour map's name, or the gradient as text (``"white,yellow,orange,red"``)."""
        if self.cmap is not None:
            return self.cmap
        gradient = self.gradient if self.gradient is not None else DEFAULT_GRADIENT
        return gradient if isinstance(gradient, str) else ",".join(str(g) for g in gradient)

    def limits(self, data: NDArray[Any] | Sequence[float] | None = None) -> tuple[float, float]:
        """``(vmin, vmax)``: as given, else from the finite values of `data` (shape any)."""
        import numpy as np
        values = np.asarray(data if data is not None else [], dtype=float).ravel()
        finite = values[np.isfinite(values)]
        center = self.center
        if self.cmap is None and self.vmin is None and self.vmax is None and center is None:
            return 0.0, float(len(self._colors) - 1)
        lo, hi = self.vmin, self.vmax
        if center is not None and lo is None and hi is None:
            with np.errstate(over="ignore"):
                half = float(np.max(np.abs(finite - center))) if finite.size else 1.0
            half = min(max(half or 1.0, abs(center) * 1e-6), BIGGEST)
            return max(center - half, -BIGGEST), min(center + half, BIGGEST)
        if finite.size and lo is None and hi is not None and hi <= float(finite.min()):
            raise BrainPainterError(
                f"vmax={hi:g} is not above the smallest value of the table ({float(finite.min()):g}); "
                f"give a larger vmax, or also a vmin below {hi:g}."
            )
        if finite.size and hi is None and lo is not None and lo >= float(finite.max()):
            raise BrainPainterError(
                f"vmin={lo:g} is not below the largest value of the table ({float(finite.max()):g}); "
                f"give a smaller vmin, or also a vmax above {lo:g}."
            )
        lo = (float(finite.min()) if finite.size else 0.0) if lo is None else lo
        hi = (float(finite.max()) if finite.size else 1.0) if hi is None else hi
        if (self.vmin is None or self.vmax is None) and hi <= lo:
            return widen(lo)
        return lo, hi

    def scale(self, data: NDArray[Any] | Sequence[float] | None = None) -> ColourScale:
        """The colour scale for a run whose values (all rows) are `data`, shape any."""
        lo, hi = self.limits(data)
        return ColourScale(
            colors=self._colors,
            vmin=float(lo),
            vmax=float(hi),
            center=None if self.center is None else float(self.center),
            nan_color=to_rgb(self.nan_color),
            missing_color=to_rgb(self.missing_color),
            name=self.name,
        )


def widen(value: float) -> tuple[float, float]:
    """A range for data with one value: ``value..value+1``, or ``1e-6 * |value|`` wide for huge values."""
    step = max(1.0, abs(value) * 1e-6)
    return (value, value + step) if value + step <= BIGGEST else (value - step, value)


def make_scale(data: NDArray[Any] | Sequence[float] | None = None,
               **options: Unpack[ScaleKwargs]) -> ColourScale:
    """Build the colour scale for a run: ``ScaleOptions(**options).scale(data)``.

    Parameters
    ----------
    data : ndarray, optional
        All values of the run, for default limits.
    **options
        gradient, cmap, vmin, vmax, center, nan_color, missing_color: see
        :class:`ScaleOptions`.
    """
    return ScaleOptions(**options).scale(data)
