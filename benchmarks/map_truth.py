"""Do a map's colours read true under the lighting? (issue 33, item 12)

Renders a constant map (2.75 on every vertex, a ``1.5``-``4`` viridis scale: the middle of
the scale) from the lateral and medial views, once with ``--shading flat`` (which pixels show
the map: exactly its colour) and once per lighting, and reads every map pixel back as the
value of the nearest colour of the colour map in CIELAB
(:func:`brainpainter.media.imagemetrics.read_values`). Prints per lighting:

- ``within``: the share of map pixels read within +-5 % of the scale's range of 2.75 (the bar:
  >= 90 % by default);
- ``L* spread``: the 90th minus 10th percentile of their CIE L* (the folds still show: >= 8).

    python benchmarks/map_truth.py [--size 800x600] [--lighting studio soft ...] [--save DIR]

``--save DIR`` writes the lit images (``{lighting}_{view}.png``) to look at.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

VALUE, VMIN, VMAX, CMAP = 2.75, 1.5, 4.0, "viridis"
VIEWS = ("lateral-left", "medial-left")
TOLERANCE = 0.05            # of the range


def render(lighting: str, size: tuple[int, int], shading: str = "default") -> dict[str, np.ndarray]:
    """The constant map from :data:`VIEWS`, RGBA (h, w, 4) per view."""
    import brainpainter

    maps = {hemi: np.full(163842, VALUE, np.float32) for hemi in ("lh", "rh")}
    result = brainpainter.render(maps, cmap=CMAP, vmin=VMIN, vmax=VMAX, views=list(VIEWS), width=size[0],
                                 height=size[1], lighting=lighting, shading=shading, progress=False)
    return {view: image for (_, view), image in result.images.items()}


def map_pixels(flat: np.ndarray) -> np.ndarray:
    """Pixels of a flat render that show the map's colour (not the underlay, background, edges)."""
    from matplotlib import colormaps

    colour = 255.0 * np.asarray(colormaps[CMAP]((VALUE - VMIN) / (VMAX - VMIN))[:3])
    mask: np.ndarray = np.linalg.norm(flat[..., :3].astype(float) - colour, axis=-1) < 3.0
    return mask


def truth(image: np.ndarray, mask: np.ndarray) -> dict[str, Any]:
    """``within`` (share of map pixels read within the tolerance) and ``spread`` (L* p90 - p10)."""
    from brainpainter.media.imagemetrics import lightness, read_values

    pixels = image[..., :3][mask]
    values = read_values(pixels, CMAP, VMIN, VMAX)
    within = float(np.mean(np.abs(values - VALUE) <= TOLERANCE * (VMAX - VMIN)))
    p10, p90 = np.percentile(lightness(pixels), [10, 90])
    return {"within": within, "spread": float(p90 - p10), "pixels": int(mask.sum())}


def measure(lightings: list[str], size: tuple[int, int],
            save: Path | None = None) -> dict[str, dict[str, Any]]:
    """:func:`truth` per lighting, over the pixels of both views together."""
    masks = {view: map_pixels(image) for view, image in render("studio", size, "flat").items()}
    out: dict[str, dict[str, Any]] = {}
    for lighting in lightings:
        images = render(lighting, size)
        if save is not None:
            from PIL import Image

            save.mkdir(parents=True, exist_ok=True)
            for view, image in images.items():
                Image.fromarray(image).save(save / f"{lighting}_{view}.png")
        stacked = np.concatenate([images[v][..., :3][masks[v]] for v in VIEWS])[None]
        out[lighting] = truth(stacked, np.ones(stacked.shape[:2], bool))
    return out


def main() -> None:
    from brainpainter.rendering.settings import LIGHTINGS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="800x600")
    parser.add_argument("--lighting", nargs="+", default=list(LIGHTINGS))
    parser.add_argument("--save", type=Path)
    args = parser.parse_args()
    w, h = (int(x) for x in args.size.split("x"))
    for lighting, r in measure(args.lighting, (w, h), args.save).items():
        print(f"{lighting:12s} within +-5 %: {100 * r['within']:5.1f} %   L* spread {r['spread']:5.1f}   "
              f"({r['pixels']} map pixels)")


if __name__ == "__main__":
    main()
