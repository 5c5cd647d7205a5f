"""Tests for the GCSA (.gcs) atlas reader and vertex labelling (tools/brainpainter_builder)."""

from __future__ import annotations

import gzip
import struct
from pathlib import Path

import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter_builder.gcsa import (
    GCSA_MAGIC,
    Gcsa,
    ico_nvertices,
    icosahedron,
    label_vertices,
    prior_nodes,
    read_gcsa,
)

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
FREESURFER = SHARED_DATA / "freesurfer"
ATLAS = "{hemi}.{atlas}aparc.atlas.acfb40.noaparc.i12.2016-08-02.gcs.gz"
REFERENCE_DKT = SHARED_DATA / "reference" / "fsaverage5-dkt" / "{hemi}.aparc.DKTatlas.annot"

# The 31 cortical regions of the DKT40 protocol: DK's 34 without bankssts, frontalpole
# and temporalpole.
DKT31 = sorted(
    """caudalanteriorcingulate caudalmiddlefrontal cuneus entorhinal fusiform
    inferiorparietal inferiortemporal insula isthmuscingulate lateraloccipital
    lateralorbitofrontal lingual medialorbitofrontal middletemporal paracentral
    parahippocampal parsopercularis parsorbitalis parstriangularis pericalcarine
    postcentral posteriorcingulate precentral precuneus rostralanteriorcingulate
    rostralmiddlefrontal superiorfrontal superiorparietal superiortemporal supramarginal
    transversetemporal""".split()
)


# --------------------------------------------------------------------------- a tiny writer


def annot(r: int, g: int, b: int) -> int:
    return r + (g << 8) + (b << 16)


UNKNOWN, REGION_A, REGION_B = annot(25, 5, 25), annot(10, 20, 30), annot(200, 100, 50)
CTAB = [("unknown", (25, 5, 25)), ("regionA", (10, 20, 30)), ("regionB", (200, 100, 50))]


def synthetic_priors(icno: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Two labels per prior node: A likely in the north, B in the south, unknown near the
    south pole. Returns labels (P, 2) and probabilities (P, 2)."""
    v, _ = icosahedron(icno)
    z = v[:, 2]
    labels = np.tile([REGION_A, REGION_B], (len(v), 1))
    probs = np.where(z[:, None] > 0, [0.9, 0.1], [0.1, 0.9])
    south = z < -0.8
    labels[south] = [UNKNOWN, REGION_B]
    probs[south] = [0.6, 0.4]
    return labels, probs


def gcsa_bytes(
    labels: np.ndarray,
    probs: np.ndarray,
    *,
    icno_priors: int = 5,
    icno_classifiers: int = 4,
    means: dict[int, float] | None = None,
    with_ctab: bool = True,
) -> bytes:
    """Serialise a GCSA the way FreeSurfer's GCSAwrite does (one mean_curvature input)."""
    means = means or {UNKNOWN: 0.0, REGION_A: -0.2, REGION_B: 0.2}
    out = [struct.pack(">Iiii", GCSA_MAGIC, 1, icno_classifiers, icno_priors)]
    name = b"mean_curvature\0"
    out.append(struct.pack(">ii", 0, len(name)) + name + struct.pack(">ii", 5, 0))
    for _ in range(ico_nvertices(icno_classifiers)):
        out.append(struct.pack(">ii", len(means), 100))
        for label, mean in means.items():
            out.append(struct.pack(">ii", label, 30))
            out.append(b"1 1 1\n%+f  \n" % mean)
            out.append(b"1 1 1\n%+f  \n" % 0.01)
    # priors: per node [nlabels, total] + per label [label, prior, 4 neighbour tables]
    # with tables 0 and 2 holding one entry (the same label, probability 1).
    p, k = labels.shape
    rec = np.zeros((p, 2 + k * 14), dtype=">u4")
    rec[:, 0] = k
    rec[:, 1] = 100
    for j in range(k):
        base = 2 + j * 14
        rec[:, base] = labels[:, j]
        rec[:, base + 1] = np.asarray(probs[:, j], dtype=">f4").view(">u4")
        for o in (base + 2, base + 8):  # tables 0 and 2 (tables 1 and 3 stay empty)
            rec[:, o : o + 2] = [6, 1]
            rec[:, o + 2] = labels[:, j]
            rec[:, o + 3] = np.float32(1.0).astype(">f4").view(">u4")
    out.append(rec.tobytes())
    if with_ctab:
        fname = b"colortable_test.txt\0"
        out.append(struct.pack(">iii", 1, -2, len(CTAB)) + struct.pack(">i", len(fname)) + fname)
        out.append(struct.pack(">i", len(CTAB)))
        for i, (nm, (r, g, b)) in enumerate(CTAB):
            raw = nm.encode() + b"\0"
            out.append(struct.pack(">ii", i, len(raw)) + raw + struct.pack(">iiii", r, g, b, 0))
    return b"".join(out)


@pytest.fixture(scope="module")
def atlas_path(tmp_path_factory) -> Path:
    labels, probs = synthetic_priors()
    path = tmp_path_factory.mktemp("gcsa") / "lh.test.gcs.gz"
    path.write_bytes(gzip.compress(gcsa_bytes(labels, probs), compresslevel=1))
    return path


@pytest.fixture(scope="module")
def atlas(atlas_path) -> Gcsa:
    return read_gcsa(atlas_path)


# --------------------------------------------------------------------------- icosahedra


@pytest.mark.parametrize("scheme", ["fsaverage", "ic4"])
@pytest.mark.parametrize("order", [0, 1, 2, 3])
def test_icosahedron_is_a_closed_unit_sphere_mesh(order, scheme):
    v, f = icosahedron(order, scheme)
    assert v.shape == (ico_nvertices(order), 3)
    assert f.shape == (20 * 4**order, 3)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-12)
    # every edge shared by exactly two faces, and faces point outwards
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert (counts == 2).all()
    p = v[f]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert (np.einsum("ij,ij->i", normals, p.mean(axis=1)) > 0).all()


def test_icosahedron_levels_are_nested_and_schemes_differ():
    v3, _ = icosahedron(3)
    v2, _ = icosahedron(2)
    np.testing.assert_array_equal(v3[: len(v2)], v2)
    a, _ = icosahedron(4, "fsaverage")
    b, _ = icosahedron(4, "ic4")
    assert not np.allclose(a, b)  # different vertex order ...
    ia = np.lexsort(np.round(a, 9).T)
    ib = np.lexsort(np.round(b, 9).T)
    np.testing.assert_allclose(a[ia], b[ib], atol=1e-12)  # ... of the same vertices


def test_icosahedron_rejects_bad_order():
    with pytest.raises(ValueError, match="order"):
        icosahedron(8)


# --------------------------------------------------------------------------- reading


def test_read_synthetic(atlas, atlas_path):
    assert atlas.source == str(atlas_path)
    assert (atlas.ninputs, atlas.icno_classifiers, atlas.icno_priors) == (1, 4, 5)
    assert atlas.inputs[0].name == "mean_curvature"
    assert (atlas.inputs[0].type, atlas.inputs[0].navgs, atlas.inputs[0].flags) == (0, 5, 0)
    assert atlas.n_prior_nodes == 10242
    assert atlas.n_classifier_nodes == 2562
    labels, probs = synthetic_priors()
    np.testing.assert_array_equal(atlas.prior_labels, labels.ravel())
    np.testing.assert_allclose(atlas.prior_probs, probs.ravel(), rtol=1e-6)
    assert atlas.gibbs_total_nbrs.shape == (2 * 10242, 4)
    np.testing.assert_array_equal(atlas.gibbs_total_nbrs[:2], [[6, 0, 6, 0], [6, 0, 6, 0]])
    assert atlas.class_means.shape == (3 * 2562, 1)
    np.testing.assert_allclose(atlas.class_means[:3, 0], [0.0, -0.2, 0.2])
    assert atlas.ctab_filename == "colortable_test.txt"
    assert atlas.ctab_names == ("unknown", "regionA", "regionB")
    np.testing.assert_array_equal(atlas.ctab_annotations, [UNKNOWN, REGION_A, REGION_B])
    assert atlas.region_names() == ["regionA", "regionB"]
    assert atlas.region_names(cortical_only=False) == ["unknown", "regionA", "regionB"]


def test_read_uncompressed_equals_gzipped(atlas, tmp_path):
    labels, probs = synthetic_priors()
    path = tmp_path / "plain.gcs"
    path.write_bytes(gcsa_bytes(labels, probs))
    plain = read_gcsa(path)
    np.testing.assert_array_equal(plain.prior_labels, atlas.prior_labels)
    np.testing.assert_array_equal(plain.prior_to_classifier, atlas.prior_to_classifier)


def test_read_without_colour_table_names_labels_by_value(tmp_path):
    labels, probs = synthetic_priors()
    path = tmp_path / "noctab.gcs"
    path.write_bytes(gcsa_bytes(labels, probs, with_ctab=False))
    g = read_gcsa(path)
    assert set(g.ctab_names) == {f"label{v}" for v in (UNKNOWN, REGION_A, REGION_B)}


def _one_line_error(path: Path) -> str:
    with pytest.raises(BrainPainterError) as info:
        read_gcsa(path)
    msg = str(info.value)
    assert "\n" not in msg
    assert str(path) in msg
    return msg


def test_not_a_gcsa_file(tmp_path):
    path = tmp_path / "lh.aparc.annot"
    path.write_bytes(b"\x00\x00\x00\x02 definitely not an atlas" * 10)
    msg = _one_line_error(path)
    assert "not a FreeSurfer GCSA atlas" in msg and "magic" in msg


def test_gzipped_non_gcsa_and_broken_gzip(tmp_path):
    path = tmp_path / "x.gcs.gz"
    path.write_bytes(gzip.compress(b"hello world, this is text"))
    assert "magic" in _one_line_error(path)
    path.write_bytes(b"\x1f\x8b\x08\x00garbage")
    assert "decompressed" in _one_line_error(path)


def test_truncated_and_missing_files(tmp_path):
    labels, probs = synthetic_priors()
    data = gcsa_bytes(labels, probs)
    path = tmp_path / "cut.gcs"
    path.write_bytes(data[: len(data) // 2])
    assert "file ends inside" in _one_line_error(path)
    path.write_bytes(data[:40])
    assert "not a valid" in _one_line_error(path)
    assert "Cannot read" in _one_line_error(tmp_path / "missing.gcs")


def test_unsupported_icosahedron_order(tmp_path):
    labels, probs = synthetic_priors(2)
    path = tmp_path / "ico2.gcs"
    path.write_bytes(gcsa_bytes(labels, probs, icno_priors=2))
    assert "icosahedron order 2" in _one_line_error(path)


# --------------------------------------------------------------------------- labelling


def test_prior_labelling_follows_priors(atlas):
    v, _ = icosahedron(5)
    np.testing.assert_array_equal(prior_nodes(atlas, v * 100.0), np.arange(len(v)))
    labels, ctab, names = label_vertices(atlas, v * 100.0)
    assert names == ["unknown", "regionA", "regionB"]
    np.testing.assert_array_equal(ctab[:, 4], [UNKNOWN, REGION_A, REGION_B])
    np.testing.assert_array_equal(ctab[:, :4], [[25, 5, 25, 0], [10, 20, 30, 0], [200, 100, 50, 0]])
    expected = np.where(v[:, 2] > 0, 1, 2)
    expected[v[:, 2] < -0.8] = 0
    np.testing.assert_array_equal(labels, expected)
    assert labels.dtype == np.int32


def test_off_grid_points_map_to_nearest_node(atlas):
    v, _ = icosahedron(5)
    jitter = v + 1e-4 * np.random.default_rng(1).standard_normal(v.shape)
    np.testing.assert_array_equal(prior_nodes(atlas, jitter), np.arange(len(v)))


def test_classifier_uses_the_curvature_likelihood(atlas):
    v, _ = icosahedron(5)
    curv = np.full(len(v), 0.2)  # region B's mean everywhere; A is 4 sd away
    labels, _, names = label_vertices(atlas, v, curv=curv, method="classifier")
    assert set(np.array(names)[labels]) == {"regionB"}
    # "auto" means classifier when curv is given, prior otherwise
    np.testing.assert_array_equal(label_vertices(atlas, v, curv=curv)[0], labels)
    prior_only = label_vertices(atlas, v, method="auto")[0]
    np.testing.assert_array_equal(prior_only, label_vertices(atlas, v, method="prior")[0])


def test_classifier_needs_curv_and_gibbs_needs_faces(atlas):
    v, _ = icosahedron(5)
    with pytest.raises(BrainPainterError, match="curv="):
        label_vertices(atlas, v, method="classifier")
    with pytest.raises(BrainPainterError, match="faces="):
        label_vertices(atlas, v, curv=np.zeros(len(v)), method="gibbs")
    with pytest.raises(BrainPainterError, match="method"):
        label_vertices(atlas, v, method="bayes")
    with pytest.raises(BrainPainterError, match="has 3 values"):
        label_vertices(atlas, v, curv=[0.0, 0.0, 0.0], method="classifier")
    with pytest.raises(BrainPainterError, match="shape"):
        label_vertices(atlas, v[:, :2])


def test_mode_filter_removes_a_single_vertex_island(tmp_path):
    labels, probs = synthetic_priors()
    v, f = icosahedron(5)
    island = int(np.argmax(v[:, 2] * (np.abs(v[:, 0]) < 0.5)))  # well inside region A
    probs[island] = [0.2, 0.8]
    path = tmp_path / "island.gcs"
    path.write_bytes(gcsa_bytes(labels, probs))
    g = read_gcsa(path)
    raw, _, names = label_vertices(g, v, faces=f, mode_filter=0)
    assert names[raw[island]] == "regionB"
    filtered, _, names = label_vertices(g, v, faces=f)
    assert names[filtered[island]] == "regionA"


def test_gibbs_runs_and_keeps_smooth_regions(atlas):
    v, f = icosahedron(5)
    curv = np.where(v[:, 2] > 0, -0.2, 0.2)
    gibbs, _, names = label_vertices(atlas, v, curv=curv, faces=f, method="gibbs")
    classifier, _, _ = label_vertices(atlas, v, curv=curv, faces=f, method="classifier")
    assert (gibbs == classifier).mean() > 0.99
    assert set(names) >= {"regionA", "regionB"}


def test_cortex_mask(atlas):
    v, f = icosahedron(5)
    south_pole = v[:, 2] < -0.8
    # inside the mask the non-cortical "unknown" is replaced by the best cortical label
    labels, _, names = label_vertices(atlas, v, cortex=np.ones(len(v), dtype=bool))
    assert set(np.array(names)[labels[south_pole]]) == {"regionB"}
    # outside it vertices are unlabelled; index arrays work too
    inside = np.flatnonzero(~south_pole)
    labels, _, names = label_vertices(atlas, v, faces=f, cortex=inside)
    assert (labels[south_pole] == -1).all()
    assert (labels[inside] >= 0).all()
    assert "unknown" not in set(np.array(names)[labels[inside]])
    with pytest.raises(BrainPainterError, match="cortex"):
        label_vertices(atlas, v, cortex=np.ones(5, dtype=bool))


def test_keep_unused_returns_whole_colour_table(tmp_path):
    labels, probs = synthetic_priors()
    labels[labels == UNKNOWN] = REGION_A  # unknown never used now
    path = tmp_path / "nounknown.gcs"
    path.write_bytes(gcsa_bytes(labels, probs))
    g = read_gcsa(path)
    v, _ = icosahedron(5)
    assert label_vertices(g, v)[2] == ["regionA", "regionB"]
    assert label_vertices(g, v, keep_unused=True)[2] == ["unknown", "regionA", "regionB"]


# --------------------------------------------------------------------------- real atlases


def _require_shared_data() -> None:
    if not (FREESURFER / "average").is_dir():
        pytest.skip(
            f"shared data not found at {SHARED_DATA} (needs ../shared/data beside the repo)"
        )


@pytest.fixture(scope="module")
def real_atlases():
    _require_shared_data()
    cache: dict[tuple[str, str], Gcsa] = {}

    def get(hemi: str, atlas: str) -> Gcsa:
        if (hemi, atlas) not in cache:
            cache[hemi, atlas] = read_gcsa(
                FREESURFER / "average" / ATLAS.format(hemi=hemi, atlas=atlas)
            )
        return cache[hemi, atlas]

    return get


def _fsaverage(hemi: str, subject: str = "fsaverage"):
    import nibabel.freesurfer as nfs

    base = FREESURFER / "subjects" / subject
    sphere, faces = nfs.read_geometry(base / "surf" / f"{hemi}.sphere.reg")
    curv = nfs.read_morph_data(base / "surf" / f"{hemi}.curv")
    cortex = nfs.read_label(base / "label" / f"{hemi}.cortex.label")
    return sphere, faces, curv, cortex


def _names(labels: np.ndarray, names: list) -> np.ndarray:
    names = [n.decode() if isinstance(n, bytes) else n for n in names]
    table = np.array([*names, "<none>"], dtype=object)
    return table[np.where(labels < 0, len(names), labels)]


@pytest.mark.integration
@pytest.mark.parametrize("hemi", ["lh", "rh"])
def test_dkt_atlas_regions(real_atlases, hemi):
    g = real_atlases(hemi, "DKT")
    assert (g.ninputs, g.icno_priors, g.icno_classifiers) == (1, 7, 4)
    assert g.inputs[0].name == "mean_curvature" and g.inputs[0].navgs == 5
    assert len(g.ctab_names) == 36  # the full Desikan-Killiany colour table is embedded
    assert sorted(g.region_names()) == DKT31
    assert len(g.region_names()) == 31
    # every prior node finds a classifier for each of its labels (checks the ic4 order)
    node = np.repeat(np.arange(g.n_prior_nodes), np.diff(g.prior_offsets))
    keys = set(
        zip(
            np.repeat(np.arange(g.n_classifier_nodes), np.diff(g.class_offsets)).tolist(),
            g.class_labels.tolist(),
            strict=True,
        )
    )
    pairs = zip(g.prior_to_classifier[node].tolist(), g.prior_labels.tolist(), strict=True)
    assert all(p in keys for p in pairs)


@pytest.mark.integration
@pytest.mark.parametrize("hemi", ["lh", "rh"])
def test_dkt_on_fsaverage_matches_reference(real_atlases, hemi):
    import nibabel.freesurfer as nfs

    reference = REFERENCE_DKT.with_name(REFERENCE_DKT.name.format(hemi=hemi))
    if not reference.is_file():
        pytest.skip(f"reference DKT annotation not found at {reference}")
    g = real_atlases(hemi, "DKT")
    sphere, faces, curv, cortex = _fsaverage(hemi)
    assert (prior_nodes(g, sphere) == np.arange(len(sphere))).all()  # fsaverage is ic7
    labels, ctab, names = label_vertices(g, sphere, curv=curv, faces=faces, cortex=cortex)
    assert sorted(n for n in names if n != "unknown") == DKT31
    assert ctab.shape == (len(names), 5)
    ours = _names(labels[:10242], names)  # fsaverage5 = the first 10242 vertices
    ref_labels, _, ref_names = nfs.read_annot(reference)
    ref = _names(ref_labels, ref_names)
    _, _, _, cortex5 = _fsaverage(hemi, "fsaverage5")
    agreement = (ours[cortex5] == ref[cortex5]).mean()
    assert agreement >= 0.95, f"{hemi}: {agreement:.4f}"


@pytest.mark.integration
def test_dk_on_fsaverage_matches_aparc(real_atlases):
    import nibabel.freesurfer as nfs

    g = real_atlases("lh", "DK")
    assert len(g.region_names()) == 34
    sphere, faces, curv, cortex = _fsaverage("lh")
    labels, _, names = label_vertices(g, sphere, curv=curv, faces=faces, cortex=cortex)
    aparc_labels, _, aparc_names = nfs.read_annot(
        FREESURFER / "subjects" / "fsaverage" / "label" / "lh.aparc.annot"
    )
    agree = _names(labels, names)[cortex] == _names(aparc_labels, aparc_names)[cortex]
    assert agree.mean() >= 0.93
