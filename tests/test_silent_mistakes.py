"""Issue 44, items 10-13: mistakes that used to pass in silence are a one-line warning or error, with the
numbers (a threshold that keeps no edge, a matrix without names on an atlas whose size others share,
streamlines outside the brain, fsLR arrays given to the other hemisphere)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError

REPO = Path(__file__).resolve().parents[1]
TINY_DK = ["Left-insula", "Left-precuneus", "Left-superiorfrontal", "Right-insula", "Right-precuneus",
           "Right-superiorfrontal"]
SMALL = {"views": "dorsal", "width": 160, "height": 120, "progress": False, "shading": "flat",
         "quality": "fast", "glass_opacity": 0.0}


def six_nodes(tmp_path) -> str:
    """The tiny template's six DK regions, every pair an edge, |weight| up to 0.9."""
    w = np.zeros((6, 6))
    iu = np.triu_indices(6, 1)
    w[iu] = np.linspace(0.1, 0.9, 15)
    path = tmp_path / "m.csv"
    rows = [",".join(["", *TINY_DK])] + [",".join([n, *map(repr, map(float, row))])
                                         for n, row in zip(TINY_DK, w + w.T, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def command(tmp_path, capsys, *args: str) -> tuple[int, list[str]]:
    """``brainpainter render`` with the stand-in renderer: exit code and the non-empty output lines."""
    from brainpainter.cli.main import main
    from brainpainter.testing import stand_in

    with stand_in() as renderer, pytest.raises(SystemExit) as exit_:
        main(["render", "--renderer", renderer, "--size", "80x60", "-q", "--out", str(tmp_path / "out"),
              "--views", "dorsal", *args])
    out = capsys.readouterr()
    return exit_.value.code or 0, [line for line in (out.out + out.err).splitlines() if line.strip()]


# -- item 11: a threshold that keeps no edge --------------------------------------------------------------
def test_a_threshold_above_every_weight_is_one_line_with_the_largest_weight(tmp_path, tiny, capsys):
    code, lines = command(tmp_path, capsys, "--connectome", six_nodes(tmp_path), "--atlas", "dk",
                          "--template", str(tiny), "--edge-threshold", "99")
    assert code == 2 and len(lines) == 1, lines
    assert "--edge-threshold 99 keeps no edge of connectome matrix" in lines[0]
    assert "largest |weight| is 0.9" in lines[0] and "'99%'" in lines[0]
    assert not (tmp_path / "out").exists()
    code, lines = command(tmp_path, capsys, "--connectome", six_nodes(tmp_path), "--atlas", "dk",
                          "--template", str(tiny), "--edge-threshold", "0.85")
    assert code == 0 and not any("keeps no edge" in line for line in lines), lines


def test_a_series_warns_for_the_matrices_a_threshold_empties_and_refuses_when_it_empties_all(tiny, tmp_path):
    (tmp_path / "nodes.csv").write_text("name,x,y,z\nleft,-35,0,20\nright,35,0,20\n")
    np.save(tmp_path / "fc.npy", np.stack([[[0.0, w], [w, 0.0]] for w in (0.2, 0.9, 0.3)]))
    kw = {"connectome": str(tmp_path / "fc.npy"), "nodes": str(tmp_path / "nodes.csv"), "template": str(tiny),
          **SMALL}
    with pytest.warns(UserWarning, match=r"--edge-threshold 0.5 keeps no edge of 2 of the 3 matrices of "
                                         r"connectome series .* their largest \|weight\| is 0.3 \(stage-1, "
                                         r"stage-3\): those images show the nodes only"):
        result = brainpainter.render(None, edge_threshold=0.5, **kw)
    assert [i["n_edges"] for i in result.manifest["connectome"]["series"]["images"]] == [0, 1, 0]
    with pytest.raises(BrainPainterError, match=r"keeps no edge of 3 of the 3 matrices .* largest \|weight\| "
                                                r"is 0.9;"):
        brainpainter.render(None, edge_threshold=1, **kw)


# -- item 10 and 15: a matrix without names, the atlases of its size ------------------------------------
SCHAEFER = REPO / "plugins" / "atlases" / "brainpainter-atlas-schaefer-yeo" / "bp_atlas_schaefer_yeo" / "data"


@pytest.fixture
def schaefer400():
    """schaefer400_7n and schaefer400_17n registered as installed atlases for the test."""
    from brainpainter.atlas import registry
    from brainpainter.atlas.model import load_atlas_dir

    names = ("schaefer400_7n", "schaefer400_17n")
    for name in names:
        registry.atlases.register(name, lambda name=name: load_atlas_dir(SCHAEFER / name), replace=True)
    yield {name: registry.get_atlas(name) for name in names}
    for name in names:
        registry.atlases.unregister(name)


def brainspace_400() -> np.ndarray:
    """The group FC matrix of Schaefer-400 in its 7-network order (brainspace's holdout group)."""
    import importlib.metadata

    try:
        dist = importlib.metadata.distribution("brainspace")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("brainspace (a test extra) is not installed")
    path = dist.locate_file("brainspace/datasets/matrices/holdout_group/"
                            "schaefer_400_mean_connectivity_matrix.csv")
    return np.loadtxt(str(path), delimiter=",")


def test_a_7_network_matrix_on_the_17_network_atlas_warns_naming_the_order_it_fits(schaefer400):
    """Issue 44 item 10: the 7- and 17-network orders are the same 400 parcels in other orders; a 7-network
    matrix given the 17-network atlas put every node in another parcel, silently."""
    from brainpainter.connectome.centroids import region_centroids
    from brainpainter.connectome.order import ordered_keys

    def place(atlas, keys):
        return region_centroids(atlas, keys, "fsaverage", "pial")

    weights = brainspace_400()
    wrong = (r"has no names; its 400 rows were placed in the node order of atlas 'schaefer400_17n', but its "
             r"weights follow the places of 'schaefer400_7n''s regions far better \(correlation of weight "
             r"with nearness 0.27 vs 0.14\): give --atlas schaefer400_7n")
    with pytest.warns(UserWarning, match=wrong) as said:
        ordered_keys(schaefer400["schaefer400_17n"], weights, "fc.csv", place=place)
    assert len(said) == 1
    right = (r"placed in the node order of atlas 'schaefer400_7n' \(its cortical regions, left hemisphere "
             r"then right, in its label order\); the atlases that take 400 rows: "
             r"schaefer400_7n, schaefer400_17n")
    with pytest.warns(UserWarning, match=right) as said:
        keys = ordered_keys(schaefer400["schaefer400_7n"], weights, "fc.csv", place=place)
    assert len(said) == 1 and "far better" not in str(said[0].message) and keys[0] == "Left-Vis_1"


def test_a_matrix_of_68_rows_on_dk_alone_is_quiet_and_without_atlas_says_dk_was_assumed(tmp_path):
    import warnings

    from brainpainter.atlas.registry import get_atlas
    from brainpainter.connectome.order import ordered_keys

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(ordered_keys(get_atlas("dk"), np.ones((68, 68)), "m.txt")) == 68
    with pytest.warns(UserWarning, match=r"has no names and no --atlas was given; its 68 rows were placed in "
                                         r"the node order of atlas 'dk'"):
        ordered_keys(get_atlas("dk"), np.ones((68, 68)), "m.txt", atlas_given=False)


@pytest.mark.parametrize("atlas", [(), ("--atlas", "dkt")])
def test_a_matrix_of_another_size_names_the_atlases_of_its_size_and_not_dk_unasked(tmp_path, capsys, atlas):
    np.savetxt(tmp_path / "m.txt", np.ones((400, 400)))
    code, lines = command(tmp_path, capsys, "--connectome", str(tmp_path / "m.txt"), *atlas)
    assert code == 2 and len(lines) == 1, lines
    assert "has 400 rows and no names" in lines[0]
    assert ("the atlases that take 400 rows: schaefer400_7n, schaefer400_17n (pip install "
            "brainpainter-atlas-schaefer-yeo)") in lines[0]
    assert ("'dk'" in lines[0]) is False
    assert ("atlas 'dkt' takes a matrix without names of 62 or 89 rows" in lines[0]) == bool(atlas)
    assert not (tmp_path / "out").exists()


# -- item 12: streamlines outside the brain ----------------------------------------------------------------
def write_tck(path, shift: float) -> str:
    """A .tck of 10 streamlines along y through the left hemisphere, moved `shift` mm along x."""
    import nibabel as nib

    t = np.linspace(-30.0, 30.0, 20)
    lines = [np.column_stack([np.full(20, -35.0 + shift + k), t, np.full(20, 20.0)]).astype(np.float32)
             for k in range(10)]
    tractogram = nib.streamlines.Tractogram(lines, affine_to_rasmm=np.eye(4))
    nib.streamlines.save(tractogram, str(path))
    return str(path)


def test_streamlines_mostly_outside_the_brain_warn_with_their_share(tmp_path, tiny):
    """Issue 44 item 12: dipy's bundles without their affine (voxel coordinates) were drawn beside the
    brain in silence."""
    import warnings

    from brainpainter.atlas.template import load_template
    from brainpainter.tracts.model import TractSpec

    template = load_template(str(tiny))
    outside = TractSpec((write_tck(tmp_path / "AF_left.tck", 200.0),), space="template")
    said = (r"^100% of the streamlines' points lie outside the brain: they span x 165\.\.174, y -30\.\.30, z "
            r"20\.\.20 mm, the template x -\d+\.\.\d+, .*Give their affine \(--tracts-affine\) or their "
            r"--tracts-space")
    with pytest.warns(UserWarning, match=said):
        outside.load(template)
    (tmp_path / "inside").mkdir()
    inside = TractSpec((write_tck(tmp_path / "inside" / "AF_left.tck", 0.0),), space="template")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(inside.load(template).lines) == 10


# -- item 13: fsLR maps given as the other hemisphere ----------------------------------------------------
FSLR = REPO.parent / "shared" / "data" / "fslr"


def test_an_fslr_map_on_the_other_hemispheres_cortex_warns(tmp_path):
    """Issue 44 item 13: HCP's right-hemisphere cortex mask (values 1 on its cortex, 0 on its medial wall)
    given to --lh was drawn on the left hemisphere in silence; the two masks differ by 106 vertices."""
    import re
    import shutil
    import warnings

    from brainpainter.maps.inputs import read_maps

    if not (FSLR / "L.atlasroi.32k_fs_LR.shape.gii").is_file():
        pytest.skip("../shared/data/fslr is not here")
    left, right = tmp_path / "roi_a.32k_fs_LR.shape.gii", tmp_path / "roi_b.32k_fs_LR.shape.gii"  # names
    shutil.copy(FSLR / "L.atlasroi.32k_fs_LR.shape.gii", left)  # that do not say the hemisphere
    shutil.copy(FSLR / "R.atlasroi.32k_fs_LR.shape.gii", right)
    said = (r"map 'roi_b.32k_fs_LR.shape.gii' given as --lh has values on exactly the right hemisphere's "
            r"fsLR cortex \(HCP's atlasroi: 29,716 vertices, 63 of them on the left hemisphere's medial "
            r"wall\): it looks like the right hemisphere's map; give it to --rh if it is\.")
    with pytest.warns(UserWarning) as caught:
        read_maps(lh=str(right), rh=str(left))
    assert len(caught) == 2 and re.fullmatch(said, str(caught[0].message)), [str(w.message) for w in caught]
    assert "'roi_a.32k_fs_LR.shape.gii' given as --rh" in str(caught[1].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_maps(lh=str(left), rh=str(right))  # the right way round: quiet
        rng = np.random.default_rng(0)
        read_maps({"lh": rng.uniform(1, 3, 32492)})  # values everywhere: nothing to tell
