"""A label map's colour bar is a key of its categories (issue 21): a block and a name for each
category the cortex shows, in the category's own colour; not a gradient of category numbers."""

from __future__ import annotations

import nibabel as nib
import numpy as np

from brainpainter.color.scale import ScaleOptions
from brainpainter.maps.inputs import read_maps
from brainpainter.maps.layers import map_scale
from brainpainter.maps.resolution import masks

N5 = 10242


def test_the_key_names_the_drawn_categories_in_their_colours(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from brainpainter.media.colorbar import draw_colorbar

    cortex = masks("lh")["cortex"][:N5]
    labels = np.where(cortex, 1 + (np.arange(N5) % 2), 0).astype(np.int32)   # wall | a, b
    ctab = np.array([[20, 20, 20, 0, 0], [230, 30, 30, 0, 1], [30, 30, 230, 0, 2]], np.int32)
    path = tmp_path / "lh.nets.annot"
    nib.freesurfer.write_annot(str(path), labels, ctab, [b"medial_wall", b"a", b"b"], fill_ctab=True)
    scale = map_scale(ScaleOptions(), read_maps(lh=path))
    assert [name for name, _ in scale.categories] == ["a", "b"]          # the wall is not drawn
    assert scale.to_dict()["categories"] == {"a": "#e61e1e", "b": "#1e1ee6"}
    fig, ax = plt.subplots(figsize=(4, 0.6), dpi=100)
    draw_colorbar(ax, scale)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a", "b"]
    fig.canvas.draw()
    pixels = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    box = ax.get_window_extent()
    y = int(fig.bbox.height - (box.y0 + box.y1) / 2)
    left, right = pixels[y, int(box.x0 + box.width * 0.25)], pixels[y, int(box.x0 + box.width * 0.75)]
    assert np.abs(left - [230, 30, 30]).max() <= 3 and np.abs(right - [30, 30, 230]).max() <= 3
    plt.close(fig)
