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


@pytest.mark.render
def test_a_map_with_a_contour_and_tracts_on_their_own_scale(tmp_path):
    """The issue's scene: a map, a contour of a mask and tracts with FA on their own scale (a map run
    drew no tracts: they were dropped without a word)."""
    from test_tracts import bundle, write

    from brainpainter import Scene

    folder = tmp_path / "bundles"
    folder.mkdir()
    write(folder / "AF_L.trk", bundle(-25.0, n=40, z=20.0, length=60.0))
    write(folder / "CST_R.tck", bundle(25.0, n=40, seed=1, z=20.0, length=60.0))
    fa = tmp_path / "fa.csv"
    fa.write_text("Image-name-unique,AF_L,CST_R\nctrl,0.3,0.7\n")
    scene = (Scene(width=320, height=240, shading="flat", quality="fast", glass_opacity=0.0)
             .add({"lh": np.linspace(1.5, 4, 10242), "rh": np.linspace(1.5, 4, 10242)}, cmap="viridis",
                  vmin=1.5, vmax=4, label="thickness (mm)")
             .add(_mask(tmp_path), outline=True)
             .add(folder, values=fa, cmap="magma", vmin=0.3, vmax=0.7, label="FA"))
    result = scene.render(views="subcortical-dorsal", progress=False, max_streamlines=40, tract_radius=1.5)
    img = next(iter(result.images.values()))[..., :3].astype(int)
    for rgb in ((0, 0, 4), (252, 253, 191)):  # FA 0.3 and 0.7: magma's ends, not viridis
        assert (np.abs(img - rgb).max(axis=-1) <= 20).sum() > 100, rgb
    assert [(la.kind, la.label, la.scale.name) for la in result.layers] == [
        ("map", "thickness (mm)", "viridis"), ("tracts", "FA", "magma")]
    assert result.manifest["settings"]["lines"] == [{"kind": "contour", "levels": [0.5]}]


def test_a_contour_that_no_level_divides_is_a_warning(tmp_path):
    """An empty mask (all 0) at level 0.5 draws no line: said (it drew nothing without a word); a mask
    of 0 and 1, or NaN beside values above the level, draws lines and says nothing."""
    import warnings

    from brainpainter.maps.options import MapOptions
    from brainpainter.rendering.composition import read_contours

    def write(values):
        nib.MGHImage(np.asarray(values, np.float32).reshape(-1, 1, 1), np.eye(4)).to_filename(
            tmp_path / "lh.mask.mgh")
        return str(tmp_path / "lh.mask.mgh")

    with pytest.warns(UserWarning, match=r"lh.mask.mgh: its values are 0..0, which no level of \[0.5\] "
                                         r"divides, so it draws no line; give --contour-levels"):
        read_contours(MapOptions(contour=write(np.zeros(10242))))
    with pytest.warns(UserWarning, match="no level of"):
        read_contours(MapOptions(contour=write(np.zeros(10242)), contour_levels="1.5,2"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_contours(MapOptions(contour=write(np.arange(10242) % 2)))
        read_contours(MapOptions(contour=write(np.where(np.arange(10242) % 2, 1.0, np.nan))))


@pytest.mark.render
def test_a_red_dashed_contour_with_black_dk_borders_each_in_its_own_line(tmp_path):
    """Issue 44 item 4: Scene takes a red contour with black DK borders (it refused: "drawn in one line
    style"); each is drawn in its own colour and width, the contour's dashes leave gaps, and a figure's
    legend names both lines in their colours."""
    import brainpainter

    table = {f"lh_{r}": 0.0 for r in LATERAL}
    image = {"gradient": "white,blue", "vmin": 0, "vmax": 1, "shading": "flat", "quality": "fast",
             "width": 480, "height": 360}
    contour = _mask(tmp_path)

    def scene(style: str) -> brainpainter.Scene:
        s = brainpainter.Scene("dk", **image)
        s.add(table)
        s.add(contour.split(","), outline=True, color="red", width=4, style=style)
        return s.add("dk", outline=True, color="black", width=2)

    from PIL import Image

    solid, dashed = (next(iter(scene(style).render("lateral-left", progress=False).images.values()))[..., :3]
                     .astype(int) for style in ("solid", "dashed"))
    Image.fromarray(np.hstack([solid, dashed]).astype(np.uint8)).save(tmp_path / "contour_outline.png")
    red = [int((np.abs(img - [255, 0, 0]).max(axis=-1) <= 10).sum()) for img in (solid, dashed)]
    black = [int((img.max(axis=-1) <= 10).sum()) for img in (solid, dashed)]
    assert red[0] > 300 and black[0] > 300  # each line in its own colour, true to it (within 10)
    assert 0.35 < red[1] / red[0] < 0.85, red  # dashes: about 3 mm of every 5
    assert abs(black[1] - black[0]) < 0.1 * black[0]  # the borders stay solid
    fig = scene("dashed").figure(views="lateral-left", progress=False)
    (legend,) = [ax.get_legend() for ax in fig.image_axes.values() if ax.get_legend() is not None]
    lines = {t.get_text(): h for t, h in zip(legend.get_texts(), legend.legend_handles, strict=True)}
    assert set(lines) == {"dk borders", "contour at 0.5"}
    assert lines["contour at 0.5"].get_color() == [1.0, 0.0, 0.0]
    assert lines["contour at 0.5"].get_linestyle() == "--" and lines["dk borders"].get_linestyle() == "-"
