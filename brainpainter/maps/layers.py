"""A map's per-vertex colours: the underlay, the data through the colour scale, threshold and medial wall.

Layers, bottom first (the conventions of nilearn and surfplot):

1. the underlay: greys from the sulcal depth of the mesh drawn (its ``sulc``), light
   on gyral crowns and dark deep in sulci, spread by ``--underlay-contrast``; without
   one, and for ``curv``, two greys from fsaverage's ``sulc`` (or ``curv``) sign
   (``none``: one grey);
2. the data, through the run's colour scale, where it is finite, on the
   cortex (not on ``cortex.label``'s medial wall) and ``|v| >= threshold``.

The colour scale's defaults (diverging only for data of both signs) are chosen by
:mod:`brainpainter.maps.autoscale`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.scale import ColourScale, ScaleOptions
from brainpainter.maps.autoscale import DEFAULT_CMAP, choose_scale
from brainpainter.maps.inputs import VertexMaps
from brainpainter.maps.outlines import OUTLINE_COLOR, border_vertices
from brainpainter.maps.resolution import masks

#: Underlay greys (sRGB): gyri, sulci, and the one grey of ``--underlay none``.
GYRUS_GREY, SULCUS_GREY, PLAIN_GREY = 0.74, 0.52, 0.72


def map_scale(options: ScaleOptions, maps: VertexMaps, threshold: float | None = None) -> ColourScale:
    """The colour scale of a map run: `options`, with defaults that suit maps.

    No ``cmap``/``gradient``: ``viridis``, or ``RdBu_r`` for data substantially of both
    signs, which are then symmetric about 0 (:func:`brainpainter.maps.autoscale.choose_scale`;
    the scale's ``chosen`` says why), over the values drawn (``|v| >= threshold``). The scale
    carries `threshold`, so that its colour bar greys out ``|v| < threshold``. A label map's
    scale carries its categories (the colour bar is their key).
    """
    data = maps.finite()
    if maps.categories is not None and maps.category_colors is not None:  # a key of the categories
        if options.cmap is None and options.gradient is None:
            options = replace(options, cmap=DEFAULT_CMAP)
        return replace(options.scale(data), categories=_drawn_categories(maps))
    shown = data[np.abs(data) >= threshold] if threshold else data
    # limits chosen over the values drawn: over all, a few blobs above --threshold 2.3 were outliers of a
    # -2.24..2.24 scale, drawn in its end colours under a bar greyed out from end to end
    options, chosen = choose_scale(options, shown if shown.size else data)
    return replace(options.scale(data), threshold=threshold, chosen=chosen)


def _drawn_categories(maps: VertexMaps) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """The categories of a label map that some cortex vertex shows (the medial wall's are not drawn)."""
    assert maps.categories is not None and maps.category_colors is not None
    used: set[int] = set()
    for hemi, values in maps.values.items():
        # coarser maps: the first n vertices are shared; the user's own surface: every vertex
        cortex = np.ones(values.shape[1], bool) if maps.own_mesh else masks(hemi)["cortex"][: values.shape[1]]
        shown = values[:, cortex]
        used.update(int(c) for c in np.unique(shown[np.isfinite(shown)]))
    return tuple((name, (float(c[0]), float(c[1]), float(c[2])))
                 for i, (name, c) in enumerate(zip(maps.categories, maps.category_colors, strict=True))
                 if i in used)


def underlay(hemi: str, source_vertex: NDArray[Any], kind: str, depth: NDArray[Any] | None = None,
             contrast: float = 1.0, mesh_masks: Mapping[str, NDArray[Any]] | None = None) -> NDArray[Any]:
    """Underlay colour of each vertex, float32 (n, 3); `source_vertex` indexes fsaverage (or `mesh_masks`).

    `depth` (shape (n,), FreeSurfer's ``sulc``: positive in sulci), for ``kind="sulc"``: greys
    scaled from it (its 2nd to 98th percentile across :data:`SULCUS_GREY` to :data:`GYRUS_GREY`
    about their middle, times `contrast`); else two greys from the sign masks of fsaverage (or of
    the user's own surface, `mesh_masks`).
    """
    sv = np.asarray(source_vertex, np.int64)
    if kind == "none":
        grey = np.full(len(sv), PLAIN_GREY, np.float32)
    elif kind == "sulc" and depth is not None and len(depth) == len(sv) and len(sv):
        grey = depth_greys(np.asarray(depth, np.float64), contrast)
    else:
        deep = (masks(hemi) if mesh_masks is None else mesh_masks)[kind][sv]
        grey = np.where(deep, SULCUS_GREY, GYRUS_GREY).astype(np.float32)
    return np.repeat(grey[:, None], 3, axis=1)


def depth_greys(depth: NDArray[Any], contrast: float = 1.0) -> NDArray[Any]:
    """Greys of sulcal depths (shape (n,), positive in sulci): darker the deeper, float32 (n,)."""
    finite = depth[np.isfinite(depth)]
    if not finite.size:
        return np.full(len(depth), 0.5 * (GYRUS_GREY + SULCUS_GREY), np.float32)
    lo, hi = np.percentile(finite, [2, 98])
    t = np.clip((np.nan_to_num(depth, nan=0.5 * (lo + hi)) - lo) / max(hi - lo, 1e-9), 0.0, 1.0)  # 0-1
    mid, half = 0.5 * (GYRUS_GREY + SULCUS_GREY), 0.5 * (GYRUS_GREY - SULCUS_GREY) * contrast
    grey: NDArray[Any] = np.clip(mid + half * (1.0 - 2.0 * t), 0.0, 1.0).astype(np.float32)
    return grey


Image = float | tuple[int, int, float]


def vertex_colors(maps: VertexMaps, image: Image, source_vertex: dict[str, NDArray[Any]], scale: ColourScale,
                  underlay_kind: str = "sulc", threshold: float | None = None,
                  cluster_edges: dict[str, NDArray[Any]] | None = None,
                  below: dict[str, NDArray[Any]] | None = None, opacity: float = 1.0,
                  depth: dict[str, NDArray[Any]] | None = None, contrast: float = 1.0,
                  mesh_masks: Mapping[str, Mapping[str, NDArray[Any]]] | None = None,
                  sample: Callable[[str, int], NDArray[Any]] | None = None,
                  ) -> dict[str, NDArray[Any]]:
    """The colours of one image of `maps` at the drawn vertices.

    Parameters
    ----------
    maps : VertexMaps
    image : float or (int, int, float)
        Which of ``maps.images``; a float between two, or ``(a, b, w)`` (a
        movie's in-between frame), blends two images' values linearly
        (``(1 - w) * a + w * b``; label maps take the nearer image).
    source_vertex : dict of str to ndarray of int, shape (n_hemi,)
        fsaverage vertex of each drawn vertex, per hemisphere.
    scale : ColourScale
    underlay_kind : {"sulc", "curv", "none"}
    threshold : float, optional
        ``|v| < threshold`` shows the underlay.
    cluster_edges : dict of str to ndarray of int, shape (m, 2), optional
        The mesh's edges: the borders of the coloured (supra-threshold) areas are outlined too.
    below : dict of str to ndarray of float, shape (n_hemi, 3), optional
        What the map is drawn over (region colours), NaN where the underlay shows.
    opacity : float
        0-1: how much the map covers what is below it.
    depth : dict of str to ndarray of float, shape (n_hemi,), optional
        Sulcal depth of the drawn vertices (the mesh's ``sulc``): the underlay's greys scale with it.
    contrast : float
        How far those greys spread (``--underlay-contrast``).
    mesh_masks : dict of str to dict of str to ndarray of bool, shape (n_surface,), optional
        Per hemisphere, the ``cortex``, ``sulc`` and ``curv`` masks (:func:`masks`) of the surface
        `source_vertex` indexes, when it is not fsaverage (the user's own surface).
    sample : callable, optional
        ``sample(hemi, i)``: image ``i`` of `hemi` at the drawn vertices, shape (n_hemi,), where they
        are not `source_vertex`'s on the map's surface (the flat maps:
        :func:`brainpainter.maps.flat.flat_values`); `source_vertex` then names the fsaverage
        vertex whose underlay and cortex mask each takes.

    Returns
    -------
    dict of str to ndarray of float32, shape (n_hemi, 3)
        sRGB 0-1.
    """
    out: dict[str, NDArray[Any]] = {}
    for hemi, sv in source_vertex.items():
        sv = np.asarray(sv, np.int64)
        own = None if mesh_masks is None else mesh_masks.get(hemi)
        rgb = underlay(hemi, sv, underlay_kind, None if depth is None else depth.get(hemi), contrast, own)
        if below is not None and hemi in below:
            under = np.asarray(below[hemi], np.float32)
            rgb = np.where(np.isnan(under), rgb, under).astype(np.float32)
        if hemi in maps.values and len(sv):
            v = _values_at(maps, hemi, image, sv, sample)
            show = np.isfinite(v) & (masks(hemi) if own is None else own)["cortex"][sv]
            if threshold is not None and maps.categories is None:
                show &= np.abs(np.where(show, v, 0.0)) >= threshold
            if maps.categories is not None and maps.category_colors is not None:
                over = maps.category_colors[v[show].astype(np.int64)]
            else:
                over = scale(v[show])[:, :3]
            rgb[show] = over if opacity >= 1.0 else (1.0 - opacity) * rgb[show] + opacity * over
            if cluster_edges is not None and hemi in cluster_edges:
                rgb[border_vertices(~show, cluster_edges[hemi])] = OUTLINE_COLOR  # the cluster's edge
        out[hemi] = np.clip(rgb, 0.0, 1.0).astype(np.float32)
    return out


def _values_at(maps: VertexMaps, hemi: str, image: Image, sv: NDArray[Any],
               sample: Callable[[str, int], NDArray[Any]] | None = None) -> NDArray[Any]:
    """Image `image` of `maps` at vertices `sv` of its surface (or as `sample` gives it); a blend of two
    (categories: nearest)."""
    def at(i: int) -> NDArray[Any]:
        return maps.on_surface(hemi, i)[sv] if sample is None else sample(hemi, i)

    categorical = maps.categories is not None
    n_images = len(maps.values[hemi])
    if isinstance(image, tuple):
        lo, hi, t = int(image[0]), int(image[1]), float(image[2])
    else:
        lo = int(np.floor(image))
        hi, t = min(lo + 1, n_images - 1), float(image) - lo
    a: NDArray[Any] = at(lo).astype(np.float64)
    if t == 0.0 or hi == lo:
        return a
    b: NDArray[Any] = at(hi).astype(np.float64)
    if categorical:
        return a if t < 0.5 else b
    mixed: NDArray[Any] = (1.0 - t) * a + t * b
    return mixed
