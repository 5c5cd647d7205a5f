"""The automatic colour scale of a map: diverging only for data of both signs, else sequential.

Decided on robust percentiles (the 2nd and 98th), so that a stray vertex does not
choose the scale (nilearn's fsaverage5 thickness has one vertex at -0.0028 among
20,484 from 0 to 4.7; on its min and max it became a diverging -4.7..4.7 with half
the colours unused):

* **both signs** when ``p2 < 0 < p98`` and the smaller side reaches at least
  :data:`MINOR_SIDE` of the larger (real data: fsaverage5 sulc 0.80, curv 0.59,
  nilearn's z-map ``image_10426`` projected 0.54; thickness and areas have no
  negative side): ``RdBu_r``, symmetric about 0;
* **one sign** (a smaller side, if any, is noise about 0 and takes the colour of 0):
  ``viridis`` from 0 when 0 is near (the robust low end within :data:`ZERO_NEAR`
  of the way from 0 to the top: thickness, areas, probabilities), else from the
  data's lowest value (a myelin map of 1.0-1.8); mirrored for values <= 0;
* the scale reaches the data's extremes, outliers excepted: values more than
  :data:`FENCE` times the 2nd-98th percentile range beyond it take the end colours.

A gradient without ``vmin``/``vmax`` keeps BrainPainter's values 0..N-1 for data of
one sign. Limits or a centre given are used as given.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.scale import ScaleOptions

#: Default colour maps of maps given no --cmap/--gradient: values of one sign, values of both signs.
DEFAULT_CMAP, DEFAULT_SIGNED_CMAP = "viridis", "RdBu_r"
#: The robust low and high ends of the data, percentiles.
PERCENTILES = (2.0, 98.0)
#: Both signs: the smaller side's robust magnitude is at least this fraction of the larger's.
MINOR_SIDE = 0.1
#: One sign: the scale starts at 0 when the robust low end is within this fraction of the top.
ZERO_NEAR = 1.0 / 3.0
#: Outliers lie beyond the robust range by more than this many times its width.
FENCE = 0.5


def choose_scale(options: ScaleOptions, data: NDArray[Any]) -> tuple[ScaleOptions, str]:
    """`options` with a map's defaults filled in, and why (empty when the limits were given).

    Parameters
    ----------
    options : ScaleOptions
    data : ndarray of float, shape (n,)
        Every value the scale colours (non-finite ones are ignored).

    Returns
    -------
    options : ScaleOptions
        With ``cmap``, and ``vmin``/``vmax``/``center`` where none were given.
    reason : str
        E.g. ``"values >= 0"``, ``"values of both signs"``; empty when limits were given.
    """
    values = np.asarray(data, dtype=np.float64).ravel()
    values = values[np.isfinite(values)]
    both = two_signed(values)
    if options.cmap is None and options.gradient is None:
        options = replace(options, cmap=DEFAULT_SIGNED_CMAP if both or options.center is not None
                          else DEFAULT_CMAP)
    if options.vmin is not None or options.vmax is not None or options.center is not None or not values.size:
        return options, ""
    lo, hi = _fenced(values)
    if both:
        half = max(abs(lo), abs(hi))
        return replace(options, vmin=-half, vmax=half, center=0.0), _with_outliers(
            "values of both signs", values, -half, half)
    if options.cmap is None:  # a gradient: BrainPainter's values 0..N-1
        return options, ""
    p_lo, p_hi = (float(p) for p in np.percentile(values, PERCENTILES))
    # a side below MINOR_SIDE of the other is noise about 0: its values take the colour of 0
    if p_hi > 0 and p_hi >= -p_lo and p_lo <= ZERO_NEAR * hi:
        lo, reason = 0.0, "values >= 0"
    elif p_lo < 0 and -p_lo > p_hi and p_hi >= ZERO_NEAR * lo:
        hi, reason = 0.0, "values <= 0"
    else:
        reason = "values of one sign, far from 0"
    if not hi > lo:  # one value: the scale about it, as ScaleOptions widens it
        return options, reason
    return replace(options, vmin=float(lo), vmax=float(hi)), _with_outliers(reason, values, lo, hi)


def two_signed(values: NDArray[Any]) -> bool:
    """Whether finite `values` (shape (n,)) are substantially of both signs (see the module's rule)."""
    if not values.size:
        return False
    p_lo, p_hi = (float(p) for p in np.percentile(values, PERCENTILES))
    return p_lo < 0 < p_hi and min(-p_lo, p_hi) >= MINOR_SIDE * max(-p_lo, p_hi)


def _fenced(values: NDArray[Any]) -> tuple[float, float]:
    """The lowest and highest of `values` that are no outliers (within the fences of the robust range)."""
    p_lo, p_hi = np.percentile(values, PERCENTILES)
    reach = FENCE * (p_hi - p_lo)
    kept = values[(values >= p_lo - reach) & (values <= p_hi + reach)]
    return float(kept.min()), float(kept.max())


def _with_outliers(reason: str, values: NDArray[Any], lo: float, hi: float) -> str:
    """`reason`, and how many values lie outside ``[lo, hi]`` (drawn in the end colours)."""
    n = int(np.count_nonzero((values < lo) | (values > hi)))
    return reason if not n else f"{reason}; {n} value(s) outside the scale take its end colours"
