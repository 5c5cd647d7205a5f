"""Lines as layers (issue 35): ``--outline ATLAS`` and ``--contour FILE`` enter every run in one place
(:func:`brainpainter.rendering.composition.line_layers`), over region values as over a map."""

from __future__ import annotations

import nibabel as nib
import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.maps.resolution import N_FSAVERAGE

LATERAL = ("superiorfrontal", "caudalmiddlefrontal", "rostralmiddlefrontal", "precentral", "postcentral",
           "supramarginal", "superiorparietal", "inferiorparietal", "lateraloccipital", "superiortemporal",
           "middletemporal", "inferiortemporal", "parsopercularis", "parstriangularis", "insula")


def _mask(tmp_path):
    """A mask of the left hemisphere anterior of y = -20 (fsaverage), as ``LH,RH`` files."""
    from brainpainter.atlas.template import load_template
    from brainpainter.maps.resolution import map_mesh

    mesh = map_mesh(load_template("fsaverage"), "dk", "lh")
    mask = np.zeros(N_FSAVERAGE, np.float32)
    mask[np.asarray(mesh.source_vertex)[mesh.vertices["pial"][:, 1] > -20]] = 1.0
    for hemi, values in (("lh", mask), ("rh", np.zeros(N_FSAVERAGE, np.float32))):
        nib.MGHImage(values.reshape(-1, 1, 1), np.eye(4)).to_filename(tmp_path / f"{hemi}.mask.mgh")
    return f"{tmp_path / 'lh.mask.mgh'},{tmp_path / 'rh.mask.mgh'}"


@pytest.mark.render
def test_a_contour_over_region_values_is_a_line_of_constant_pixel_width(tmp_path):
    """``render table.csv --contour mask``: the mask's edge over the region colours (it was refused), at
    constant pixel width (twice the size, about twice the line's pixels); without --outline no region
    border is drawn, with it both are."""
    from brainpainter import render

    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique," + ",".join(f"lh_{r}" for r in LATERAL) + "\nctrl,"
                     + ",".join("1" for _ in LATERAL) + "\n")
    contour = _mask(tmp_path)
    image = {"gradient": "white,red", "vmin": 0, "vmax": 1, "shading": "flat", "quality": "fast",
             "views": "lateral-left", "progress": False, "outline_color": "black"}

    def dark(size, **more):
        result = render(table, width=size, height=size * 3 // 4, **image, **more)
        img = next(iter(result.images.values()))
        return int((img[..., :3].astype(int).max(axis=-1) < 40).sum()), result

    assert dark(240)[0] == 0  # red regions, grey medial wall: nothing dark
    small, result = dark(240, contour=contour, outline_width=2)
    large = dark(480, contour=contour, outline_width=2)[0]
    assert small > 100 and 1.5 <= large / small <= 3.0, (small, large)
    assert result.manifest["settings"]["lines"] == [{"kind": "contour", "levels": [0.5]}]
    both = dark(240, contour=contour, outline="dk", outline_width=2)
    assert both[0] > small + 100  # the regions' borders too
    assert [la["kind"] for la in both[1].manifest["settings"]["lines"]] == ["outline", "contour"]


def test_an_outline_of_another_atlas_is_refused_over_region_values(tmp_path):
    from brainpainter.rendering.run import prepare_run

    message = r"^a region render outlines its own atlas's regions \('dk'\); --outline 'destrieux' was given\."
    with pytest.raises(BrainPainterError, match=message):
        prepare_run({"lh_insula": [1.0]}, outline="destrieux")
