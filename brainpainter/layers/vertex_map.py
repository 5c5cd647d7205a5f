"""The map layer's colours: a per-vertex map on the cortex (over its underlay, thresholded, with the
region values below it where given) and a volume's means in the subcortical structures.

:class:`MapColors` is a map run's first layer (:attr:`brainpainter.rendering.run.Run.base`);
each image is a :class:`VertexColors`: region colours plus each hemisphere's vertex colours.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.color.scale import ColourScale
from brainpainter.layers.kinds import RGB
from brainpainter.layers.regions import region_colors
from brainpainter.maps.flat import flat_values
from brainpainter.maps.inputs import VertexMaps
from brainpainter.maps.layers import vertex_colors
from brainpainter.maps.options import MapOptions

#: One image of a map: an image's index, or a movie's frame ``(a, b, weight)`` between two.
Image = float | tuple[int, int, float]


class VertexColors(Mapping[str, RGB]):
    """One image of a map: region colours (a mapping, as for a region image) plus per-vertex cortex colours.

    Parameters
    ----------
    regions : mapping of str to (r, g, b)
        Colours of region keys (the subcortical structures).
    vertices : mapping of str to ndarray of float32, shape (n_vertices, 3)
        sRGB 0-1 per cortex vertex of each hemisphere (:attr:`SceneGeometry.vertex_slots`).
    """

    def __init__(self, regions: Mapping[str, RGB], vertices: Mapping[str, NDArray[Any]]) -> None:
        self.regions = dict(regions)
        self.vertices = dict(vertices)

    def __getitem__(self, key: str) -> RGB:
        return self.regions[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.regions)

    def __len__(self) -> int:
        return len(self.regions)

    def __or__(self, over: Mapping[str, RGB]) -> VertexColors:
        """These colours with `over` (the layers drawn over the map: tracts, a connectome) added."""
        return VertexColors({**self.regions, **over}, self.vertices)


@dataclass
class MapColors:
    """The colours of a map's images.

    Parameters
    ----------
    maps : VertexMaps
    atlas : Atlas
        The atlas whose structures take a volume's means.
    scale : ColourScale
        The map layer's.
    opacity : float
        The map layer's (0-1 over the underlay).
    options : MapOptions
        The underlay, its contrast and the threshold.
    source_vertex : dict of str to ndarray of int, shape (n_hemi,)
        Each drawn cortex vertex's vertex of the map's surface.
    cluster_edges, depth, mesh_masks, flat, flat_edges, below
        See :func:`brainpainter.maps.layers.vertex_colors`: the outline's mesh edges, the sulcal depth,
        the user's surface's masks, the flat sheets' nearest vertices and edges, the region values
        under the map (:class:`~brainpainter.rendering.composition.RegionsBelow`).
    """

    maps: VertexMaps
    atlas: Atlas
    scale: ColourScale
    opacity: float
    options: MapOptions
    source_vertex: dict[str, NDArray[Any]]
    cluster_edges: dict[str, NDArray[Any]] | None = None
    depth: dict[str, NDArray[Any]] | None = None
    mesh_masks: dict[str, dict[str, NDArray[Any]]] | None = None
    flat: dict[str, NDArray[Any]] | None = None
    flat_edges: dict[str, NDArray[Any]] | None = None
    below: Any = None
    #: How the painter colours the cortex: one colour per vertex.
    coloring: ClassVar[str] = "vertices"
    _cache: dict[Any, VertexColors] = field(default_factory=dict, repr=False)

    def colors(self, image: Image, over: Mapping[str, RGB]) -> VertexColors:
        """The colours of image `image` (or ``(a, b, w)``: images a and b blended), with `over` added."""
        return self._colors(image) | over

    def blend(self, a: int, b: int, weight: float, over: Mapping[str, RGB]) -> VertexColors:
        """Images `a` and `b` blended, ``(1 - weight) * a + weight * b`` (a movie's frame), with `over`."""
        return self.colors((a, b, float(weight)) if a != b and weight else a, over)

    def _colors(self, image: Image) -> VertexColors:
        if image not in self._cache:
            self._cache.clear()  # one image at a time: the views of a row share it
            m, scale = self.options, self.scale
            map_image: Image = image if self.maps.n_images > 1 else 0
            regions: dict[str, Any] = {}
            below = None
            row = round(image if not isinstance(image, tuple) else image[0] if image[2] < 0.5 else image[1])
            if self.below is not None:  # region values under the map: a movie's frame takes the nearer row
                regions, below = self.below.colors(row)
            cortex = vertex_colors(self.maps, map_image, self.source_vertex, scale, m.underlay, m.threshold,
                                   cluster_edges=self.cluster_edges, below=below, opacity=self.opacity,
                                   depth=self.depth, contrast=m.underlay_contrast, mesh_masks=self.mesh_masks)
            if self.flat is not None:  # the flat maps' vertices: the map's values there, the same layers
                on_flat = vertex_colors(
                    self.maps, map_image, self.flat, scale, m.underlay, m.threshold,
                    cluster_edges=self.flat_edges,
                    below=None if below is None else {h: below[f"flat-{h}"] for h in self.flat},
                    opacity=self.opacity, contrast=m.underlay_contrast,
                    sample=lambda hemi, i: flat_values(self.maps, hemi, i))
                cortex.update({f"flat-{hemi}": rgb for hemi, rgb in on_flat.items()})
            # a volume's subcortical means: below --threshold a structure shows no value, as the cortex does
            means = {k: v for k, v in self.maps.region_values(map_image).items()
                     if m.threshold is None or abs(v) >= m.threshold}
            means_rgb = region_colors(means, self.atlas, scale)
            regions.update(means_rgb if self.below is None else {k: means_rgb[k] for k in means})
            self._cache[image] = VertexColors(regions, cortex)
        return self._cache[image]
