"""brainpainter's own layer kinds, registered in its ``pyproject.toml`` (``brainpainter.layers``)
as a plugin registers its own; each is drawn by its command-line flags (``brainpainter layers``)."""

from __future__ import annotations

from brainpainter.layers.kinds import LayerKind

_SCALE = {"cmap": "a matplotlib colour map", "gradient": "control colours (white,yellow,red)",
          "vmin": "value at the first colour", "vmax": "value at the last colour",
          "center": "diverging: value at the middle colour", "label": "colour-bar label"}


def _scaled(prefix: str) -> dict[str, str]:
    return {f"{prefix}-{name}": text for name, text in _SCALE.items()}


regions = LayerKind("regions", "a value per atlas region (a table: INPUT)", _scaled("--regions"),
                    ("INPUT", "--atlas"))
vertex_map = LayerKind("map", "a value per vertex: surface maps, CIFTI, an MNI152 volume projected",
                {**_scaled("--map"), "--map-alpha": "opacity over region colours",
                 "--threshold": "values below are not drawn"}, ("INPUT", "--lh", "--rh", "--volume"))
tracts = LayerKind("tracts", "white-matter bundles as tubes, coloured by bundle values or direction",
                   _scaled("--tracts"), ("--tracts", "--tract-values"))
connectome = LayerKind("connectome", "a connectivity matrix: nodes as spheres, edges as cylinders",
                       {**_scaled("--edges"), **_scaled("--nodes")}, ("--connectome", "--nodes"))
contour = LayerKind("contour", "a second map's iso-lines over the cortex",
                    {"--contour-levels": "values of the lines", "--contour-color": "colour",
                     "--contour-width": "pixels", "--contour-style": "solid or dashed"}, ("--contour",))
outline = LayerKind("outline", "an atlas's region borders over the cortex",
                    {"--outline-color": "colour", "--outline-width": "pixels",
                     "--outline-style": "solid or dashed"}, ("--outline",))
blobs = LayerKind("blobs", "an MNI152 volume's clusters as lit surfaces",
                  {**_scaled("--blobs"), "--min-cluster-mm3": "smaller clusters are not drawn"},
                  ("--volume-surface",))
