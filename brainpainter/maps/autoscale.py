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
  ``viridis`` over the robust range, the 2nd to the 98th percentile of the values
  that are not 0 (as Workbench's default palette: the zeros of a medial wall or of
  a thresholded map do not choose it), its end toward 0 narrowed to Tukey's fence
  (the medial wall's partial values), so that most of the cortex is not one
  colour: nilearn's fsaverage5 thickness (0-4.7) gets 1.08-3.53 (it was 0-4.7,
  which put 90 % of the cortex in a third of the bar, one green; now in 64 %);
  from 0 where the values reach it (the low end within :data:`ZERO_NEAR` of the
  top: probabilities, counts); mirrored for values <= 0. Values beyond take the
  end colours, and the reason says how many;
* **both signs**: the scale reaches the data's extremes, outliers excepted: values
  more than :data:`FENCE` times the 2nd-98th percentile range beyond it take the end
  colours.

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
ZERO_NEAR = 0.05
#: One sign: the end toward 0 is cut at this many interquartile ranges beyond the quartile (Tukey's fence).
TUKEY = 1.5
#: One sign: an end of the robust range this close to the data's extreme (a fraction of the range) is it.
REACH = 0.05
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
    lo, hi = _robust(values)
    # a side below MINOR_SIDE of the other is noise about 0: its values take the colour of 0
    if hi > 0 and hi >= -lo and lo <= ZERO_NEAR * hi:
        lo, reason = 0.0, "values >= 0"
    elif lo < 0 and -lo > hi and hi >= ZERO_NEAR * lo:
        hi, reason = 0.0, "values <= 0"
    elif hi > 0 and hi >= -lo:
        lo, reason = max(lo, 0.0), "values >= 0, over their 2nd-98th percentiles"
    elif lo < 0:
        hi, reason = min(hi, 0.0), "values <= 0, over their 2nd-98th percentiles"
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


def _robust(values: NDArray[Any]) -> tuple[float, float]:
    """The robust range of data of one sign: the 2nd and 98th percentiles of `values` that are not 0 (all
    of them where every one is 0), the end toward 0 narrowed to Tukey's fence (:data:`TUKEY` times the
    interquartile range beyond the quartile): the medial wall's partial values of a thickness map lie there,
    while the far end, where effects are, keeps its percentile. An end whose percentile is within
    :data:`REACH` of the range from the data's extreme is that extreme (evenly spread data keep their
    ends)."""
    nonzero = values[values != 0]
    base = nonzero if nonzero.size and np.ptp(nonzero) > 0 else values  # a 0/1 mask: all of them
    p_lo, q1, q3, p_hi = (float(p) for p in np.percentile(base, (PERCENTILES[0], 25, 75, PERCENTILES[1])))
    fence = TUKEY * (q3 - q1)
    if fence <= 0:  # half the values or more are one value (a mask): no fence
        pass
    elif p_hi > 0 and p_hi >= -p_lo:  # values >= 0: the low end is the one toward 0
        p_lo = max(p_lo, q1 - fence)
    else:
        p_hi = min(p_hi, q3 + fence)
    near = REACH * (p_hi - p_lo)
    low, high = float(base.min()), float(base.max())
    return (low if p_lo - low <= near else p_lo), (high if high - p_hi <= near else p_hi)


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
