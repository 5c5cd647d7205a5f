"""Reference image of an atlas: every region in its colour-table colour, with a legend.

``brainpainter atlas show NAME --image FILE`` draws the chosen views side by
side through :meth:`brainpainter.rendering.painter.Painter.paint_colors` (so with the real
renderer and the atlas's own label set) and writes a legend of region names
and colours below them, so users can see which region is which.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.errors import BrainPainterError


def atlas_colors(atlas: Atlas) -> dict[str, tuple[float, float, float]]:
    """Region key -> sRGB 0-1 colour from the atlas's look-up table."""
    return {r.key: (r.color[0] / 255, r.color[1] / 255, r.color[2] / 255) for r in atlas.regions}


def _legend(entries: list[tuple[str, tuple[int, int, int]]], width: int) -> NDArray[Any]:
    """RGBA legend, shape (h, width, 4): a swatch and a name per entry, in columns."""
    from PIL import Image, ImageDraw, ImageFont

    try:
        font = ImageFont.load_default(size=14)
    except TypeError:  # Pillow < 10.1: fixed-size bitmap font
        font = ImageFont.load_default()
    longest = max((font.getlength(n) for n, _ in entries), default=0)
    col_w = int(longest) + 34
    n_cols = max(1, width // col_w)
    n_rows = -(-len(entries) // n_cols)
    row_h = 20
    img = Image.new("RGBA", (width, 12 + n_rows * row_h), (255, 255, 255, 255))
    draw = ImageDraw.Draw(img)
    for i, (name, rgb) in enumerate(entries):
        x, y = 10 + (i // n_rows) * col_w, 6 + (i % n_rows) * row_h
        draw.rectangle([x, y + 2, x + 16, y + 16], fill=(*rgb, 255), outline=(80, 80, 80, 255))
        draw.text((x + 22, y + 1), name, fill=(0, 0, 0, 255), font=font)
    return np.asarray(img)


#: Most region names drawn in a reference image's legend; atlases with more get none.
MAX_LEGEND = 120


def reference_image(atlas: Atlas, path: str | Path, *, views: str = "lateral-left,medial-left,subcortical",
                    size: tuple[int, int] = (800, 600), template: str = "fsaverage", surface: str = "pial",
                    quality: str = "default", renderer: str = "blender", legend: bool = True) -> NDArray[Any]:
    """Draw `atlas` in its own colours from `views` and write a PNG to `path`.

    Returns
    -------
    ndarray of uint8, shape (h, w, 4)
        The image written.
    """
    from brainpainter import __version__
    from brainpainter.io.output import write_png
    from brainpainter.rendering.options import Options
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.parallel import Item, paint_all
    from brainpainter.rendering.run import make_runner
    from brainpainter.rendering.views import parse_views

    path = Path(path)
    if not path.parent.is_dir():
        raise BrainPainterError(f"folder {path.parent} of --image {path} does not exist; create it first")
    if path.suffix.lower() != ".png":
        raise BrainPainterError(f"--image must be a .png file; {path.name!r} was given")
    # the options of a run, checked as for every command (a reference image has no table to read)
    options = Options.of({"views": views, "width": size[0], "height": size[1], "template": template,
                          "surface": surface, "quality": quality, "renderer": renderer}, "reference_image")
    scene = options.scene
    view_list = parse_views(views)
    painter = Painter(atlas, scene.template, scene.surface, (), options.settings, scene.renderer)
    colors = atlas_colors(atlas)
    with make_runner(painter, scene.template) as runner:  # serial: one painter in this process
        panels = paint_all(runner, [Item(colors, v, label=atlas.name) for v in view_list])
    image: NDArray[Any] = np.concatenate(panels, axis=1)
    if legend:
        kinds = {"cortical" if v.content == "cortex" else "subcortical" for v in view_list}
        first: dict[str, tuple[int, int, int]] = {}
        for r in atlas.regions:
            if r.kind in kinds:
                first.setdefault(r.name, r.color)
        entries = list(first.items())
        if 0 < len(entries) <= MAX_LEGEND:  # a legend of hundreds of parcels (Schaefer) reads as noise
            image = np.concatenate([image, _legend(entries, image.shape[1])], axis=0)
    from brainpainter.io.transaction import FileTransaction

    with FileTransaction(path) as tx:  # locked, staged, verified, published atomically
        write_png(tx.tmp, image, {"Software": f"brainpainter {__version__}", "brainpainter:atlas": atlas.name,
                                  "brainpainter:views": ",".join(v.name for v in view_list)})
        tx.commit(size=(image.shape[1], image.shape[0]))
    return image
