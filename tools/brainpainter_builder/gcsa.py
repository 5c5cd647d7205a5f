"""Read FreeSurfer GCSA cortical-parcellation atlases (``.gcs``) and label surfaces with them.

A GCSA ("Gaussian Classifier Surface Atlas", FreeSurfer ``utils/gcsa.cpp``) is what
``mris_ca_label`` uses to parcellate a cortical surface. FreeSurfer 7.3.2 ships the
Desikan-Killiany (DK) and Desikan-Killiany-Tourville (DKT40) atlases as
``average/?h.{DK,DKT}aparc.atlas.acfb40.noaparc.i12.2016-08-02.gcs`` but no DKT
annotation for fsaverage, so the template builder derives one with this module.

File layout (all binary numbers big-endian 32-bit; matrices are ASCII, as written by
FreeSurfer's ``MatrixAsciiWriteInto``)::

    int   magic = 0xababcdcd
    int   ninputs, icno_classifiers, icno_priors
    ninputs x { int type; int len; char name[len]; int navgs; int flags }
    for each vertex of icosahedron(icno_classifiers):            # "classifiers"
        int nlabels; int total_training
        nlabels x { int label; int total_training;
                    ascii "type rows cols\\n" + values (means, ninputs x 1);
                    ascii "type rows cols\\n" + values (covariance, ninputs x ninputs) }
    for each vertex of icosahedron(icno_priors):                 # "priors"
        int nlabels; int total_training
        nlabels x { int label; float prior;
                    4 x { int total_nbrs; int n; n x { int nbr_label; float nbr_prior } } }
    optional tags: int tag (1 = colour table) + binary colour table (CTABwriteIntoBinary)

Labels are FreeSurfer annotation values ``r + g << 8 + b << 16`` of the embedded colour
table (for both acfb40 atlases the 36-entry ``colortable_desikan_killiany.txt``; the DKT40
atlas never makes bankssts, frontalpole, temporalpole or corpuscallosum the most likely
label, so :meth:`Gcsa.region_names` gives 31 cortical regions for it and 34 for DK).

Icosahedra. Priors and classifiers live on FreeSurfer's ``lib/bem/ic<k>.tri``, which
:func:`icosahedron` regenerates: ic7 (priors) in fsaverage's vertex order (checked:
identical order and faces to fsaverage and fsaverage5, coordinates within 0.005 mm at
radius 100), ic4 (classifiers) in ``ic4.tri``'s own order, which is *not* the first 2562
vertices of ic7 (inferred from the atlases: with it, every one of the 163842 prior nodes
finds a classifier for each of its labels at its classifier node, as training
guarantees; with ic7's prefix only 8.5 % do). Surfaces are mapped onto the atlas by nearest prior
node on the unit sphere, like ``GCSAsourceToPriorVertex``; for fsaverage that is the
identity.

Labelling (:func:`label_vertices`) follows ``mris_ca_label``: classify, mode-filter
(10 passes over the 2-ring), apply the cortex mask. Classification methods:

``"prior"``
    Most probable label of the vertex's prior node (``GCSAbuildMostLikelyLabels``).
``"classifier"``
    Maximum posterior: prior times the Gaussian likelihood of the inputs
    (``GCSANclassify``). The acfb40 atlases have one input, ``mean_curvature`` averaged
    5 times (FreeSurfer computes it on ``?h.smoothwm``; for fsaverage pass ``?h.curv``).
``"gibbs"``
    ``"classifier"`` refined by ICM with the atlas's neighbourhood priors
    (``GCSAreclassifyUsingGibbsPriors``), with the tables of the two principal-curvature
    directions pooled.

Agreement on fsaverage (``?h.curv`` as input, 2-ring mode filter, ``?h.cortex.label``):

=============  ===========================  ==============================
method         DK vs fsaverage aparc,       DKT vs reference fsaverage5 DKT,
               cortex vertices (lh / rh)    fsaverage5 cortex (lh / rh)
=============  ===========================  ==============================
prior          94.87 % / 95.13 %            97.81 % / 97.63 %
classifier     95.09 % / 95.26 %            98.05 % / 97.75 %
gibbs          95.06 % / 95.19 %            98.01 % / 97.86 %
=============  ===========================  ==============================

(``"prior"`` with no mesh, i.e. no filter and no mask: DK 93.37 / 93.77 %, DKT 97.54 /
97.30 %.) ``"classifier"`` is the default whenever ``curv`` is given; ``"gibbs"`` is no
better and four times slower (about 7 s against 1.6 s per fsaverage hemisphere).
"""

from __future__ import annotations

import gzip
import re
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse
from scipy.spatial import cKDTree

from brainpainter.errors import BrainPainterError, choice_error

__all__ = [
    "GCSA_MAGIC",
    "METHODS",
    "NON_CORTICAL_NAMES",
    "Gcsa",
    "GcsaInput",
    "ico_nvertices",
    "icosahedron",
    "label_vertices",
    "prior_nodes",
    "read_gcsa",
]

GCSA_MAGIC = 0xABABCDCD
TAG_OLD_COLORTABLE = 1
GIBBS_SURFACE_NEIGHBORS = 4
GCSA_INPUT_CURVATURE = 0
GCSA_INPUT_CURV_FILE = 1
GCSA_NORMALIZE = 0x1
METHODS = ("prior", "classifier", "gibbs")
#: Colour-table names that are not cortical regions (FreeSurfer's medial-wall labels).
NON_CORTICAL_NAMES = frozenset({"unknown", "corpuscallosum", "medial_wall"})
BIG_AND_NEGATIVE = -10000000.0
MAX_ICO_ORDER = 7
_TIE_TOLERANCE = 2e-4

_WHITESPACE = b" \t\n\r\v\f"
_MATRIX_HEADER = re.compile(rb"\s*(-?\d+)\s+(-?\d+)\s+(-?\d+)[ \t\r]*\n")
_FLOAT = re.compile(rb"\s*([-+]?(?:nan|inf|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?))", re.IGNORECASE)

# FreeSurfer's icosahedron 0 (lib/bem/ic0.tri): faces in file order, each oriented
# outwards and rotated so that subdivision reproduces ic1..ic7 vertex and face order.
_ICO0_FACES = np.array(
    [
        [0, 3, 4], [0, 4, 5], [0, 5, 1], [0, 1, 2], [0, 2, 3],
        [3, 2, 8], [3, 8, 9], [3, 9, 4], [4, 9, 10], [4, 10, 5],
        [5, 10, 6], [5, 6, 1], [1, 6, 7], [1, 7, 2], [2, 7, 8],
        [8, 11, 9], [9, 11, 10], [10, 11, 6], [6, 11, 7], [7, 11, 8],
    ],
    dtype=np.int64,
)  # fmt: skip


# --------------------------------------------------------------------------- icosahedra


def ico_nvertices(order: int) -> int:
    """Number of vertices of the order-``order`` icosahedron: ``10 * 4**order + 2``."""
    return 10 * 4**order + 2


def _ico0_vertices() -> NDArray[np.float64]:
    """The 12 unit vertices of FreeSurfer's ic0 (north pole first, south pole last)."""
    z = 1.0 / np.sqrt(5.0)
    r = 2.0 / np.sqrt(5.0)
    upper = np.deg2rad([-72.0, 0.0, 72.0, 144.0, -144.0])
    lower = np.deg2rad([-108.0, -36.0, 36.0, 108.0, 180.0])
    v = np.zeros((12, 3))
    v[0] = (0.0, 0.0, 1.0)
    v[1:6] = np.column_stack([r * np.cos(upper), r * np.sin(upper), np.full(5, z)])
    v[6:11] = np.column_stack([r * np.cos(lower), r * np.sin(lower), np.full(5, -z)])
    v[11] = (0.0, 0.0, -1.0)
    return v


#: Icosahedron construction per order, as used by FreeSurfer's ``lib/bem/ic<order>.tri``.
#: "fsaverage": the ordering of fsaverage (ic7) and fsaverage5, checked vertex by vertex
#: and face by face; ic5/ic6 are prefixes of it. "ic4": FreeSurfer's ic4.tri, which is
#: *not* a prefix of ic7 (base rotated by 72 degrees about z, children kept together per
#: parent face); inferred from the DK/DKT atlases' classifier statistics, whose classifier
#: nodes follow it.
ICO_SCHEMES = {4: "ic4", 5: "fsaverage", 6: "fsaverage", 7: "fsaverage"}

_ICO_CACHE: dict[tuple[int, str], tuple[NDArray[np.float64], NDArray[np.int64]]] = {}


def icosahedron(
    order: int, scheme: str = "fsaverage"
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A FreeSurfer icosahedron of the given order, on the unit sphere.

    Each level keeps the previous level's vertices first and appends the normalised
    midpoints of its edges, created face by face along the edges (a, c), (c, b), (b, a)
    of each face [a, b, c].

    Parameters
    ----------
    order : int
        0 to 7.
    scheme : {"fsaverage", "ic4"}
        ``"fsaverage"``: vertex order and faces of fsaverage (order 7) and fsaverage5
        (order 5) exactly; coordinates agree with FreeSurfer's (rounded to 0.01 mm at
        radius 100) to within 5e-5. ``"ic4"``: the vertex order of FreeSurfer's
        ``lib/bem/ic4.tri`` (GCSA classifier nodes); see :data:`ICO_SCHEMES`.

    Returns
    -------
    vertices : ndarray of float64, shape (10 * 4**order + 2, 3)
        Unit vectors.
    faces : ndarray of int64, shape (20 * 4**order, 3)
        Outward-oriented triangles.
    """
    if not 0 <= order <= MAX_ICO_ORDER:
        raise ValueError(f"icosahedron order must be 0..{MAX_ICO_ORDER}; {order} was given")
    if scheme not in ("fsaverage", "ic4"):
        raise ValueError(f"icosahedron scheme must be 'fsaverage' or 'ic4'; {scheme!r} was given")
    cached = _ICO_CACHE.get((order, scheme))
    if cached is None:
        cached = _make_icosahedron(order, scheme)
        _ICO_CACHE[(order, scheme)] = cached
    return cached[0].copy(), cached[1].copy()


def _make_icosahedron(order: int, scheme: str) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    v = _ico0_vertices()
    if scheme == "ic4":
        v = v[[0, 2, 3, 4, 5, 1, 7, 8, 9, 10, 6, 11]]  # rotated by +72 degrees about z
    f = _ICO0_FACES.copy()
    for _ in range(order):
        nv, nf = len(v), len(f)
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        edges = np.stack([np.stack([a, c], 1), np.stack([c, b], 1), np.stack([b, a], 1)], 1)
        edges = edges.reshape(-1, 2)
        key = np.minimum(edges[:, 0], edges[:, 1]) * nv + np.maximum(edges[:, 0], edges[:, 1])
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        rank = np.empty(len(first), dtype=np.int64)
        rank[np.argsort(first)] = np.arange(len(first))
        mids = (nv + rank[inverse]).reshape(nf, 3)
        new_edges = edges[np.sort(first)]
        m = v[new_edges[:, 0]] + v[new_edges[:, 1]]
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        v = np.vstack([v, m])
        m_ac, m_bc, m_ab = mids[:, 0], mids[:, 1], mids[:, 2]
        children = [
            np.stack([a, m_ab, m_ac], 1),
            np.stack([m_ac, m_bc, c], 1),
            np.stack([m_ab, m_bc, m_ac], 1),
            np.stack([m_ab, b, m_bc], 1),
        ]
        if scheme == "fsaverage":  # corner-at-a children first, then the rest per parent
            rest = np.stack(children[1:], 1).reshape(-1, 3)
            f = np.vstack([children[0], rest])
        else:  # all four children per parent together
            f = np.stack(children, 1).reshape(-1, 3)
    return v, f


def _gcsa_icosahedron(order: int, what: str, source: str) -> NDArray[np.float64]:
    scheme = ICO_SCHEMES.get(order)
    if scheme is None:
        raise BrainPainterError(
            f"GCSA atlas {source!r} puts its {what} on icosahedron order {order}; only orders "
            f"{sorted(ICO_SCHEMES)} have a known FreeSurfer vertex order."
        )
    return icosahedron(order, scheme)[0]


# --------------------------------------------------------------------------- data model


@dataclass(frozen=True)
class GcsaInput:
    """One classifier input of a GCSA (``GCSA_INPUT``).

    Attributes
    ----------
    type : int
        0: mean curvature of the surface (``GCSA_INPUT_CURVATURE``);
        1: a curvature file such as ``sulc`` (``GCSA_INPUT_CURV_FILE``).
    name : str
        ``"mean_curvature"`` or the curvature file name.
    navgs : int
        Neighbourhood-averaging iterations FreeSurfer applies to it.
    flags : int
        Bit 1: normalise (``GCSA_NORMALIZE``).
    """

    type: int
    name: str
    navgs: int
    flags: int


@dataclass(frozen=True, eq=False)
class Gcsa:
    """A GCSA cortical-parcellation atlas, as read by :func:`read_gcsa`.

    ``P`` = number of prior nodes (vertices of icosahedron ``icno_priors``),
    ``C`` = number of classifier nodes (icosahedron ``icno_classifiers``),
    ``m`` = total (prior node, label) entries, ``c`` = total (classifier node, label)
    entries, ``g`` = total neighbour-label entries, ``k`` = colour-table entries,
    ``d`` = ``ninputs``. Labels are FreeSurfer annotation values ``r + g*256 + b*65536``.

    Attributes
    ----------
    source : str
        The file it was read from.
    ninputs, icno_classifiers, icno_priors : int
        Header values.
    inputs : tuple of GcsaInput, length d
    prior_offsets : ndarray of int64, shape (P + 1,)
        Node ``i``'s entries are ``prior_offsets[i]:prior_offsets[i + 1]``.
    prior_labels : ndarray of int32, shape (m,)
    prior_probs : ndarray of float32, shape (m,)
        Prior probability of each label at its node.
    prior_total_training : ndarray of int32, shape (P,)
    gibbs_offsets : ndarray of int64, shape (4 * m + 1,)
        Entry ``j``'s neighbour table ``t`` (0..3) is
        ``gibbs_offsets[4*j + t]:gibbs_offsets[4*j + t + 1]``.
    gibbs_labels : ndarray of int32, shape (g,)
    gibbs_probs : ndarray of float32, shape (g,)
        Probability of a neighbour having that label given the entry's label.
    gibbs_total_nbrs : ndarray of int32, shape (m, 4)
    class_offsets : ndarray of int64, shape (C + 1,)
    class_labels : ndarray of int32, shape (c,)
    class_total_training : ndarray of int32, shape (c,)
    class_means : ndarray of float64, shape (c, d)
    class_covs : ndarray of float64, shape (c, d, d)
        Covariances after FreeSurfer's ``gcsaFixSingularCovarianceMatrices``.
    prior_to_classifier : ndarray of int64, shape (P,)
        Classifier node of each prior node (nearest on the sphere; where two are
        equally near, the one that has a classifier for every label of the prior node,
        which is how the atlas was trained).
    ctab_filename : str
        Name of the colour table the atlas was built with ("" if none embedded).
    ctab_index : ndarray of int32, shape (k,)
        Structure index of each colour-table entry.
    ctab_names : tuple of str, length k
    ctab_rgbt : ndarray of int32, shape (k, 4)
        Red, green, blue, transparency (0 = opaque) of each entry.
    """

    source: str
    ninputs: int
    icno_classifiers: int
    icno_priors: int
    inputs: tuple[GcsaInput, ...]
    prior_offsets: NDArray[np.int64] = field(repr=False)
    prior_labels: NDArray[np.int32] = field(repr=False)
    prior_probs: NDArray[np.float32] = field(repr=False)
    prior_total_training: NDArray[np.int32] = field(repr=False)
    gibbs_offsets: NDArray[np.int64] = field(repr=False)
    gibbs_labels: NDArray[np.int32] = field(repr=False)
    gibbs_probs: NDArray[np.float32] = field(repr=False)
    gibbs_total_nbrs: NDArray[np.int32] = field(repr=False)
    class_offsets: NDArray[np.int64] = field(repr=False)
    class_labels: NDArray[np.int32] = field(repr=False)
    class_total_training: NDArray[np.int32] = field(repr=False)
    class_means: NDArray[np.float64] = field(repr=False)
    class_covs: NDArray[np.float64] = field(repr=False)
    prior_to_classifier: NDArray[np.int64] = field(repr=False)
    ctab_filename: str = ""
    ctab_index: NDArray[np.int32] = field(default_factory=lambda: np.zeros(0, np.int32))
    ctab_names: tuple[str, ...] = ()
    ctab_rgbt: NDArray[np.int32] = field(default_factory=lambda: np.zeros((0, 4), np.int32))

    @property
    def n_prior_nodes(self) -> int:
        """Number of prior nodes ``P``."""
        return len(self.prior_offsets) - 1

    @property
    def n_classifier_nodes(self) -> int:
        """Number of classifier nodes ``C``."""
        return len(self.class_offsets) - 1

    @property
    def ctab_annotations(self) -> NDArray[np.int32]:
        """Annotation value ``r + g*256 + b*65536`` of each colour-table entry, shape (k,)."""
        rgb = self.ctab_rgbt[:, :3].astype(np.int64)
        return (rgb[:, 0] + (rgb[:, 1] << 8) + (rgb[:, 2] << 16)).astype(np.int32)

    def used_labels(self) -> NDArray[np.int32]:
        """Sorted annotation values that are the most probable label of some prior node.

        Labels that occur in the priors only with small probabilities (the DKT40 atlas
        keeps traces of bankssts, frontalpole and temporalpole, each below 3%) are left
        out.

        Returns
        -------
        ndarray of int32, shape (u,)
        """
        return np.unique(self.prior_labels[_best_prior_entries(self)])

    def region_names(self, *, cortical_only: bool = True) -> list[str]:
        """Names of the colour-table entries the atlas can assign, in colour-table order.

        Parameters
        ----------
        cortical_only : bool
            Drop :data:`NON_CORTICAL_NAMES` (unknown, corpuscallosum, Medial_wall).
        """
        used = np.isin(self.ctab_annotations, self.used_labels())
        names = [n for n, u in zip(self.ctab_names, used, strict=True) if u]
        if cortical_only:
            names = [n for n in names if n.lower() not in NON_CORTICAL_NAMES]
        return names


def _best_prior_entries(gcsa: Gcsa) -> NDArray[np.int64]:
    """Entry index of the most probable label of each non-empty prior node (first if tied)."""
    counts = np.diff(gcsa.prior_offsets)
    nonempty = np.flatnonzero(counts > 0)
    if not len(nonempty):
        return np.zeros(0, dtype=np.int64)
    node_of = np.repeat(np.arange(len(counts)), counts)
    probs = gcsa.prior_probs.astype(np.float64)
    best = np.full(len(counts), -np.inf)
    np.maximum.at(best, node_of, probs)
    is_best = probs == best[node_of]
    idx = np.flatnonzero(is_best)
    _, first = np.unique(node_of[idx], return_index=True)
    return idx[first]


# --------------------------------------------------------------------------- reading


class _Reader:
    """Cursor over the decompressed bytes; raises ``ValueError`` on malformed data."""

    def __init__(self, buf: bytes) -> None:
        self.buf = buf
        self.pos = 0

    def need(self, n: int, what: str) -> None:
        if self.pos + n > len(self.buf):
            raise ValueError(f"file ends inside {what} (offset {self.pos})")

    def int(self, what: str) -> int:
        self.need(4, what)
        v = int.from_bytes(self.buf[self.pos : self.pos + 4], "big", signed=True)
        self.pos += 4
        return v

    def bytes(self, n: int, what: str) -> bytes:
        if n < 0:
            raise ValueError(f"negative length {n} for {what}")
        self.need(n, what)
        out = self.buf[self.pos : self.pos + n]
        self.pos += n
        return out

    def cstring(self, n: int, what: str) -> str:
        return self.bytes(n, what).split(b"\0", 1)[0].decode("latin-1")

    def ascii_matrix(self, rows: int, cols: int, what: str) -> NDArray[np.float64]:
        """Parse ``MatrixAsciiWriteInto`` output like ``MatrixAsciiReadFrom`` (scanf)."""
        m = _MATRIX_HEADER.match(self.buf, self.pos)
        if m is None:
            raise ValueError(f"expected an ASCII matrix header for {what} (offset {self.pos})")
        _, r, c = (int(g) for g in m.groups())
        if (r, c) != (rows, cols):
            raise ValueError(f"{what} is {r}x{c}, expected {rows}x{cols}")
        self.pos = m.end()
        out = np.empty(rows * cols)
        for i in range(rows * cols):
            fm = _FLOAT.match(self.buf, self.pos)
            if fm is None:
                raise ValueError(f"bad number in {what} (offset {self.pos})")
            out[i] = float(fm.group(1))
            self.pos = fm.end()
        # scanf's trailing "  " and "\n" consume any whitespace after the numbers.
        while self.pos < len(self.buf) and self.buf[self.pos] in _WHITESPACE:
            self.pos += 1
        return out.reshape(rows, cols)


def _decompress(raw: bytes) -> bytes:
    if raw[:2] == b"\x1f\x8b":
        return gzip.decompress(raw)
    return raw


def read_gcsa(path: str | Path) -> Gcsa:
    """Read a FreeSurfer GCSA atlas (``.gcs``, or gzipped ``.gcs.gz``).

    Parameters
    ----------
    path : str or Path
        The atlas file. Gzip compression is detected from the content, not the name.

    Returns
    -------
    Gcsa
        Header, priors (with neighbourhood priors), classifiers (covariances
        regularised as FreeSurfer's ``GCSAread`` does) and the embedded colour table.

    Raises
    ------
    BrainPainterError
        One line naming the file, if it cannot be read or is not a GCSA file.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise BrainPainterError(
            f"Cannot read GCSA atlas {str(path)!r}: {exc.strerror or exc}."
        ) from None
    try:
        buf = _decompress(raw)
    except (OSError, EOFError, zlib.error) as exc:
        raise BrainPainterError(
            f"{str(path)!r} is not a FreeSurfer GCSA atlas (.gcs): "
            f"it looks gzipped but cannot be decompressed ({exc})."
        ) from None
    if len(buf) < 16 or int.from_bytes(buf[:4], "big") != GCSA_MAGIC:
        raise BrainPainterError(
            f"{str(path)!r} is not a FreeSurfer GCSA atlas (.gcs): expected the magic number "
            f"0x{GCSA_MAGIC:08x} at its start (optionally gzipped)."
        )
    try:
        return _parse(buf, str(path))
    except ValueError as exc:
        raise BrainPainterError(
            f"{str(path)!r} is not a valid FreeSurfer GCSA atlas (.gcs): {exc}."
        ) from None


def _parse(buf: bytes, source: str) -> Gcsa:
    r = _Reader(buf)
    ninputs, icno_classifiers, icno_priors, inputs = _read_header(r)
    classes = _read_classifiers(r, ico_nvertices(icno_classifiers), ninputs)
    priors = _read_priors(buf, r, ico_nvertices(icno_priors))
    ctab = _read_tags(r, priors["prior_labels"])
    prior_to_classifier = _map_priors_to_classifiers(
        icno_priors,
        icno_classifiers,
        priors["prior_offsets"],
        priors["prior_labels"],
        classes["class_offsets"],
        classes["class_labels"],
        source,
    )
    return Gcsa(source=source, ninputs=ninputs, icno_classifiers=icno_classifiers, icno_priors=icno_priors,
                inputs=tuple(inputs), **priors, **classes, prior_to_classifier=prior_to_classifier, **ctab)


def _read_header(r: _Reader) -> tuple[int, int, int, list[GcsaInput]]:
    """Input count, classifier and prior icosahedron orders, and the inputs (curvature, sulc...)."""
    r.int("magic")
    ninputs = r.int("header")
    icno_classifiers = r.int("header")
    icno_priors = r.int("header")
    if not 1 <= ninputs <= 10:
        raise ValueError(f"ninputs is {ninputs}, expected 1..10")
    for name, order in (("classifier", icno_classifiers), ("prior", icno_priors)):
        if not 0 <= order <= MAX_ICO_ORDER:
            raise ValueError(f"{name} icosahedron order is {order}, expected 0..{MAX_ICO_ORDER}")
    inputs = []
    for i in range(ninputs):
        itype = r.int(f"input {i}")
        n = r.int(f"input {i}")
        name = r.cstring(n, f"input {i} name")
        navgs = r.int(f"input {i}")
        flags = r.int(f"input {i}")
        inputs.append(GcsaInput(itype, name, navgs, flags))
    return ninputs, icno_classifiers, icno_priors, inputs


def _read_classifiers(r: _Reader, n_class: int, ninputs: int) -> dict[str, NDArray[Any]]:
    """The ``class_*`` arrays of :class:`Gcsa` (few nodes, ico4: 2562; ASCII matrices: a plain loop)."""
    class_counts = np.zeros(n_class, dtype=np.int64)
    c_labels: list[int] = []
    c_train: list[int] = []
    c_means: list[NDArray[np.float64]] = []
    c_covs: list[NDArray[np.float64]] = []
    for vno in range(n_class):
        nlabels = r.int(f"classifier node {vno}")
        if not 0 <= nlabels <= 100000:
            raise ValueError(f"classifier node {vno} has {nlabels} labels")
        r.int(f"classifier node {vno}")  # node total_training
        class_counts[vno] = nlabels
        for _ in range(nlabels):
            c_labels.append(r.int(f"classifier node {vno}"))
            c_train.append(r.int(f"classifier node {vno}"))
            c_means.append(r.ascii_matrix(ninputs, 1, f"classifier node {vno} means")[:, 0])
            c_covs.append(r.ascii_matrix(ninputs, ninputs, f"classifier node {vno} covariance"))
    class_train = np.asarray(c_train, dtype=np.int32)
    covs = np.asarray(c_covs, dtype=np.float64).reshape(-1, ninputs, ninputs)
    return {"class_offsets": _offsets(class_counts), "class_labels": np.asarray(c_labels, dtype=np.int32),
            "class_total_training": class_train,
            "class_means": np.asarray(c_means, dtype=np.float64).reshape(-1, ninputs),
            "class_covs": _fix_singular_covariances(covs, class_train)}


def _read_priors(buf: bytes, r: _Reader, n_prior: int) -> dict[str, NDArray[Any]]:
    """The ``prior_*`` and ``gibbs_*`` arrays of :class:`Gcsa` (4-byte fields: an int32 view and a cursor)."""
    start = r.pos
    words = np.frombuffer(buf, dtype=">i4", count=(len(buf) - start) // 4, offset=start)
    w = words.tolist()
    p = 0
    prior_counts = np.zeros(n_prior, dtype=np.int64)
    prior_train = np.zeros(n_prior, dtype=np.int32)
    p_label_pos: list[int] = []  # word index of each entry's label (prior follows it)
    g_counts: list[int] = []  # per (entry, table)
    g_total: list[int] = []
    g_pos: list[int] = []  # word index of each neighbour (label, prob) pair
    try:
        for vno in range(n_prior):
            nlabels = w[p]
            if not 0 <= nlabels <= 100000:
                raise ValueError(f"prior node {vno} has {nlabels} labels")
            prior_counts[vno] = nlabels
            prior_train[vno] = w[p + 1]
            p += 2
            for _ in range(nlabels):
                p_label_pos.append(p)
                p += 2
                for _t in range(GIBBS_SURFACE_NEIGHBORS):
                    g_total.append(w[p])
                    n = w[p + 1]
                    if not 0 <= n <= 100000:
                        raise ValueError(f"prior node {vno} has {n} neighbour labels")
                    g_counts.append(n)
                    p += 2
                    g_pos.extend(range(p, p + 2 * n, 2))
                    p += 2 * n
    except IndexError:
        raise ValueError(f"file ends inside the priors (prior node {vno})") from None
    r.pos = start + 4 * p
    floats = words.view(">f4")
    lp = np.asarray(p_label_pos, dtype=np.int64)
    gp = np.asarray(g_pos, dtype=np.int64)
    gibbs_offsets = np.zeros(len(g_counts) + 1, dtype=np.int64)
    np.cumsum(g_counts, out=gibbs_offsets[1:])
    return {"prior_offsets": _offsets(prior_counts), "prior_labels": words[lp].astype(np.int32),
            "prior_probs": floats[lp + 1].astype(np.float32), "prior_total_training": prior_train,
            "gibbs_offsets": gibbs_offsets,
            "gibbs_labels": words[gp].astype(np.int32) if len(gp) else np.zeros(0, np.int32),
            "gibbs_probs": floats[gp + 1].astype(np.float32) if len(gp) else np.zeros(0, np.float32),
            "gibbs_total_nbrs": np.asarray(g_total, dtype=np.int32).reshape(-1, GIBBS_SURFACE_NEIGHBORS)}


def _read_tags(r: _Reader, prior_labels: NDArray[np.int32]) -> dict[str, Any]:
    """The ``ctab_*`` fields of :class:`Gcsa` from the trailing tags (FreeSurfer ignores unknown tags)."""
    ctab = None
    while len(r.buf) - r.pos >= 4:
        tag = r.int("tag")
        if tag == TAG_OLD_COLORTABLE:
            ctab = _read_ctab(r)
            break
    if ctab is None:  # no embedded table: name the labels after their values
        values = np.unique(prior_labels).tolist()
        rgbt = [[v & 255, (v >> 8) & 255, (v >> 16) & 255, 0] for v in values]
        ctab = ("", list(range(len(values))), [f"label{v}" for v in values], rgbt)
    filename, index, names, rgbt_rows = ctab
    return {"ctab_filename": filename, "ctab_index": np.asarray(index, dtype=np.int32),
            "ctab_names": tuple(names), "ctab_rgbt": np.asarray(rgbt_rows, dtype=np.int32).reshape(-1, 4)}


def _offsets(counts: NDArray[np.int64]) -> NDArray[np.int64]:
    """CSR offsets from counts: shape (len(counts) + 1,)."""
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def _map_priors_to_classifiers(
    icno_priors: int,
    icno_classifiers: int,
    prior_offsets: NDArray[np.int64],
    prior_labels: NDArray[np.int32],
    class_offsets: NDArray[np.int64],
    class_labels: NDArray[np.int32],
    source: str,
) -> NDArray[np.int64]:
    """Nearest classifier node of every prior node, ties broken by label coverage."""
    pri = _gcsa_icosahedron(icno_priors, "priors", source)
    cls = _gcsa_icosahedron(icno_classifiers, "classifiers", source)
    k = min(2, len(cls))
    dist, idx = cKDTree(cls).query(pri, k=k)
    dist = dist.reshape(len(pri), k)
    idx = idx.reshape(len(pri), k)
    out = idx[:, 0].astype(np.int64)
    if k < 2:
        return out
    # FreeSurfer's .tri coordinates are rounded to 1e-4 of the radius, so near-ties
    # (within twice that) may have gone either way there: let the training data decide.
    tie = np.flatnonzero(dist[:, 1] - dist[:, 0] < _TIE_TOLERANCE)
    if not len(tie):
        return out
    # coverage: how many of the prior node's labels the classifier node knows
    pcount = np.diff(prior_offsets)
    pnode = np.repeat(np.arange(len(pcount), dtype=np.int64), pcount)
    in_tie = np.zeros(len(pcount), dtype=bool)
    in_tie[tie] = True
    sel = np.flatnonzero(in_tie[pnode])
    ckeys = np.repeat(np.arange(len(class_offsets) - 1, dtype=np.int64), np.diff(class_offsets))
    ckeys = np.sort(ckeys * (1 << 25) + class_labels.astype(np.int64))
    cover = np.zeros((len(pcount), 2))
    for j in range(2):
        q = idx[pnode[sel], j].astype(np.int64) * (1 << 25) + prior_labels[sel].astype(np.int64)
        pos = np.minimum(np.searchsorted(ckeys, q), max(len(ckeys) - 1, 0))
        hit = (ckeys[pos] == q) if len(ckeys) else np.zeros(len(q), dtype=bool)
        np.add.at(cover[:, j], pnode[sel], hit.astype(np.float64))
    better = cover[tie, 1] > cover[tie, 0]
    out[tie[better]] = idx[tie[better], 1]
    return out


def _read_ctab(r: _Reader) -> tuple[str, list[int], list[str], list[list[int]]]:
    """``CTABreadFromBinary``: version 1 (count > 0) or version 2 (-2)."""
    first = r.int("colour table")
    index: list[int] = []
    names: list[str] = []
    rgbt: list[list[int]] = []
    if first > 0:  # version 1: `first` entries, implicit structure numbers
        fname = r.cstring(r.int("colour table"), "colour table name")
        for i in range(first):
            names.append(r.cstring(r.int("colour table"), "colour table entry"))
            rgbt.append([r.int("colour table") for _ in range(4)])
            index.append(i)
    elif first == -2:
        nentries = r.int("colour table")
        fname = r.cstring(r.int("colour table"), "colour table name")
        nread = r.int("colour table")
        if not 0 <= nread <= max(nentries, 0):
            raise ValueError(f"colour table has {nread} entries of at most {nentries}")
        for _ in range(nread):
            structure = r.int("colour table")
            if not 0 <= structure < nentries or structure in index:
                raise ValueError(f"bad colour table structure number {structure}")
            index.append(structure)
            names.append(r.cstring(r.int("colour table"), "colour table entry"))
            rgbt.append([r.int("colour table") for _ in range(4)])
    else:
        raise ValueError(f"unknown colour table version {-first}")
    return fname, index, names, rgbt


def _fix_singular_covariances(
    covs: NDArray[np.float64], total_training: NDArray[np.int32]
) -> NDArray[np.float64]:
    """Regularise covariances like FreeSurfer's ``gcsaFixSingularCovarianceMatrices``.

    Parameters
    ----------
    covs : ndarray, shape (c, d, d)
    total_training : ndarray, shape (c,)

    Returns
    -------
    ndarray, shape (c, d, d)
    """
    covs = covs.copy()
    if len(covs) == 0:
        return covs
    d = covs.shape[1]
    nparams = d * (d + 1) // 2 + d
    det = np.linalg.det(covs)
    tt = total_training.astype(np.float64)
    enough = ((tt == 0) & (det > 1)) | (tt * d > 2.5 * nparams)
    if enough.any():
        var = np.diagonal(covs[enough], axis1=1, axis2=2).mean(axis=0)
        min_det = float(np.prod(var)) / 100.0**d
    else:
        var = np.zeros(d)
        min_det = 1e-7
    singular = det <= 0
    ill = ((tt * d < 2 * nparams) & (det < 0.1)) | ((det < min_det) & (tt < 4 * nparams))
    fix = singular | ill
    idx = np.arange(d)
    covs[np.ix_(np.flatnonzero(fix), idx, idx)] += np.diag(var)[None]
    return covs


# --------------------------------------------------------------------------- labelling


def prior_nodes(gcsa: Gcsa, sphere_reg: ArrayLike) -> NDArray[np.int64]:
    """Prior node of each surface vertex: the nearest icosahedron vertex by direction.

    Parameters
    ----------
    gcsa : Gcsa
    sphere_reg : array_like, shape (n, 3)
        Registered sphere, any radius.

    Returns
    -------
    ndarray of int64, shape (n,)
        For fsaverage's ``?h.sphere.reg`` this is ``arange(163842)``; for fsaverage5's,
        ``arange(10242)``.
    """
    sph = np.asarray(sphere_reg, dtype=np.float64)
    if sph.ndim != 2 or sph.shape[1] != 3 or len(sph) == 0:
        raise BrainPainterError(f"sphere_reg must have shape (n, 3); {sph.shape} was given.")
    return _nearest_nodes(sph, _gcsa_icosahedron(gcsa.icno_priors, "priors", gcsa.source))


def _nearest_nodes(points: NDArray[np.float64], ico: NDArray[np.float64]) -> NDArray[np.int64]:
    norms = np.linalg.norm(points, axis=1, keepdims=True)
    norms[norms == 0] = 1.0
    _, idx = cKDTree(ico).query(points / norms)
    return np.asarray(idx, dtype=np.int64)


def _adjacency(faces: NDArray[np.int64], n: int) -> sparse.csr_matrix:
    """Binary vertex adjacency (1-ring, no self) of a triangle mesh, shape (n, n)."""
    f = np.asarray(faces, dtype=np.int64)
    i = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    j = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    keep = i != j  # degenerate faces must not make self-neighbours
    i, j = i[keep], j[keep]
    a = sparse.csr_matrix((np.ones(len(i), dtype=np.float64), (i, j)), shape=(n, n))
    a.data[:] = 1.0  # duplicates summed -> binary
    return a


def _average(values: NDArray[np.float64], adj: sparse.csr_matrix, navgs: int) -> NDArray:
    """``MRISaverageCurvatures``: each pass replaces a value by its 1-ring+self mean."""
    deg = np.asarray(adj.sum(axis=1)).ravel() + 1.0
    out = values.astype(np.float64)
    for _ in range(navgs):
        out = (out + adj @ out) / deg
    return out


def _node_candidates(
    gcsa: Gcsa, nodes: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
    """Prior-entry indices per vertex, padded: shape (n, K) and validity mask (n, K)."""
    start = gcsa.prior_offsets[nodes]
    count = gcsa.prior_offsets[nodes + 1] - start
    kmax = max(int(count.max()) if len(count) else 0, 1)
    k = np.arange(kmax)
    valid = k[None, :] < count[:, None]
    entries = np.where(valid, start[:, None] + k[None, :], 0)
    return entries, valid


def _class_lookup(
    gcsa: Gcsa, class_nodes: NDArray[np.int64], labels: NDArray[np.int32]
) -> NDArray[np.int64]:
    """Index of the classifier entry for ``labels`` at ``class_nodes`` (-1 if absent).

    Parameters
    ----------
    class_nodes, labels : ndarray, same shape (any)

    Returns
    -------
    ndarray of int64, same shape
    """
    # Key classifier entries by (node, label) and binary-search.
    counts = np.diff(gcsa.class_offsets)
    node_of = np.repeat(np.arange(gcsa.n_classifier_nodes, dtype=np.int64), counts)
    keys = node_of * (1 << 25) + gcsa.class_labels.astype(np.int64)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    q = class_nodes.astype(np.int64) * (1 << 25) + labels.astype(np.int64)
    pos = np.searchsorted(sorted_keys, q)
    pos_c = np.minimum(pos, len(sorted_keys) - 1)
    found = (len(sorted_keys) > 0) & (sorted_keys[pos_c] == q)
    return np.where(found, order[pos_c], -1)


def _log_likelihood(
    gcsa: Gcsa, centries: NDArray[np.int64], x: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Gaussian log-likelihood (up to a constant) of inputs ``x`` under entries.

    Parameters
    ----------
    centries : ndarray of int64, shape (n, K); -1 = no classifier
    x : ndarray, shape (n, d)

    Returns
    -------
    ndarray, shape (n, K); ``-inf`` where there is no classifier.
    """
    ok = centries >= 0
    ce = np.where(ok, centries, 0)
    means = gcsa.class_means[ce]  # (n, K, d)
    covs = gcsa.class_covs
    sign, logdet = np.linalg.slogdet(covs)
    bad = sign <= 0  # GCSANclassify's fallback for singular matrices: add 0.1 * I
    if bad.any():
        covs = covs.copy()
        covs[bad] += 0.1 * np.eye(covs.shape[1])
        sign, logdet = np.linalg.slogdet(covs)
    inv = np.linalg.pinv(covs, hermitian=True)  # (c, d, d)
    diff = x[:, None, :] - means
    maha = np.einsum("nki,nkij,nkj->nk", diff, inv[ce], diff)
    ll = -0.5 * maha - 0.5 * logdet[ce]
    return np.where(ok, ll, -np.inf)


def _inputs_matrix(
    gcsa: Gcsa,
    n: int,
    curv: ArrayLike | None,
    sulc: ArrayLike | None,
    adj: sparse.csr_matrix | None,
) -> NDArray[np.float64]:
    cols = []
    for inp in gcsa.inputs:
        if inp.type == GCSA_INPUT_CURVATURE or inp.name in ("curv", "mean_curvature"):
            values, what = curv, "curv"
        elif inp.name == "sulc":
            values, what = sulc, "sulc"
        else:
            raise BrainPainterError(
                f"GCSA atlas {gcsa.source!r} needs input {inp.name!r}, which label_vertices "
                "does not support (only mean curvature and sulc)."
            )
        if values is None:
            raise BrainPainterError(
                f"GCSA atlas {gcsa.source!r} classifies on {inp.name!r}: pass {what}= "
                "(one value per vertex) or use method='prior'."
            )
        arr = np.asarray(values, dtype=np.float64).reshape(-1)
        if len(arr) != n:
            raise BrainPainterError(
                f"{what} has {len(arr)} values but the sphere has {n} vertices."
            )
        if inp.navgs > 0 and adj is not None:
            arr = _average(arr, adj, inp.navgs)
        if inp.flags & GCSA_NORMALIZE:
            sd = arr.std()
            arr = (arr - arr.mean()) / (sd if sd > 0 else 1.0)
        cols.append(arr)
    return np.column_stack(cols)


def label_vertices(gcsa: Gcsa, sphere_reg: ArrayLike, *, curv: ArrayLike | None = None,
                   sulc: ArrayLike | None = None, faces: ArrayLike | None = None,
                   cortex: ArrayLike | None = None, method: str = "auto", mode_filter: int = 10,
                   keep_unused: bool = False) -> tuple[NDArray[np.int32], NDArray[np.int32], list[str]]:
    """Label surface vertices with a GCSA atlas.

    Each vertex is mapped to the nearest prior node (vertex of icosahedron
    ``icno_priors``) by direction from the sphere's centre, and through it to a
    classifier node, as FreeSurfer's ``GCSAsourceToPriorVertex`` and
    ``GCSAsourceToClassifierVertex`` do. For fsaverage (icosahedron 7) the
    vertex-to-node mapping is the identity. Then, like ``mris_ca_label``: classify
    (``method``), mode-filter (``mode_filter``), and apply the cortex mask (``cortex``).

    Parameters
    ----------
    gcsa : Gcsa
        From :func:`read_gcsa`.
    sphere_reg : array_like, shape (n, 3)
        The surface's registered sphere (``?h.sphere.reg``), any radius.
    curv : array_like, shape (n,), optional
        Mean curvature per vertex, before averaging: the acfb40 atlases' single input,
        ``mean_curvature`` (FreeSurfer computes it on ``?h.smoothwm``; for fsaverage
        use ``?h.curv``). Averaged ``navgs`` (5) times over the mesh when ``faces`` is
        given. Needed by ``"classifier"`` and ``"gibbs"``.
    sulc : array_like, shape (n,), optional
        Sulcal depth, for atlases with a ``sulc`` input (not the acfb40 ones).
    faces : array_like of int, shape (f, 3), optional
        Triangles of the surface. Needed by ``"gibbs"``, for input averaging and for the
        mode filter.
    cortex : array_like, optional
        Cortex mask, bool of shape (n,) or vertex indices (``?h.cortex.label``).
        Vertices outside get -1. Vertices inside that end up unlabelled or with a
        non-cortical label (:data:`NON_CORTICAL_NAMES`) get the best cortical label of
        their node, or, where it has none, the most common label of their labelled
        neighbours (FreeSurfer's ``relabel_unknowns_with_cortex_label``, simplified).
    method : {"auto", "prior", "classifier", "gibbs"}
        ``"prior"``: most probable label of the prior node. ``"classifier"``: maximum
        posterior, prior times the Gaussian likelihood of the inputs. ``"gibbs"``:
        ``"classifier"`` refined with the neighbourhood priors (ICM). ``"auto"``:
        ``"classifier"`` when ``curv`` (or ``sulc``) is given, else ``"prior"``.
    mode_filter : int
        Iterations of the mode filter over each vertex and its 2-ring (``mris_ca_label``
        default: 10); applied only when ``faces`` is given. 0 disables it.
    keep_unused : bool
        Return the whole embedded colour table instead of only the labels the atlas can
        assign (:meth:`Gcsa.used_labels`, plus any label actually assigned).

    Returns
    -------
    labels : ndarray of int32, shape (n,)
        Index into ``ctab`` and ``names`` per vertex; -1 = unlabelled.
    ctab : ndarray of int32, shape (k, 5)
        Red, green, blue, transparency, annotation value per region, as
        ``nibabel.freesurfer.read_annot`` returns.
    names : list of str, length k
        Region names.

    Raises
    ------
    BrainPainterError
        Unknown method, badly shaped arrays, or inputs the method needs are missing.
    """
    if method not in (*METHODS, "auto"):
        raise choice_error("method", method, (*METHODS, "auto"))
    if method == "auto":
        method = "classifier" if curv is not None or sulc is not None else "prior"
    sph, adj = _check_surface(sphere_reg, faces, method)
    cortex_mask = _cortex_mask(cortex, len(sph))
    lab, scored = _classify(gcsa, sph, method, curv, sulc, adj)
    if adj is not None and mode_filter > 0:
        lab = _mode_filter(gcsa, lab, adj, mode_filter)
    if cortex_mask is not None:
        _relabel_cortex(gcsa, lab, cortex_mask, scored, sph, adj)
    return _to_annot(gcsa, lab, keep_unused)


def _check_surface(sphere_reg: ArrayLike, faces: ArrayLike | None,
                   method: str) -> tuple[NDArray[np.float64], sparse.csr_matrix | None]:
    """The sphere as an (n, 3) array and the mesh adjacency (None without `faces`), checked."""
    sph = np.asarray(sphere_reg, dtype=np.float64)
    if sph.ndim != 2 or sph.shape[1] != 3 or len(sph) == 0:
        raise BrainPainterError(f"sphere_reg must have shape (n, 3); {sph.shape} was given.")
    n = len(sph)
    if faces is None:
        if method == "gibbs":
            raise BrainPainterError("method='gibbs' needs faces= (the surface's triangles).")
        return sph, None
    fa = np.asarray(faces)
    if (
        fa.ndim != 2
        or fa.shape[1] != 3
        or not np.issubdtype(fa.dtype, np.integer)
        or (fa.size and (fa.min() < 0 or fa.max() >= n))
    ):
        raise BrainPainterError(
            f"faces must be an (f, 3) integer array of vertex indices below {n}; "
            f"shape {fa.shape} ({fa.dtype}) was given."
        )
    return sph, _adjacency(fa.astype(np.int64), n)


def _classify(gcsa: Gcsa, sph: NDArray[np.float64], method: str, curv: ArrayLike | None,
              sulc: ArrayLike | None, adj: sparse.csr_matrix | None) -> tuple[
        NDArray[np.int64], tuple[NDArray[np.int64], NDArray[np.float64]]]:
    """Label per vertex by `method`, and each vertex's (candidate labels, scores), shape (n, k)."""
    n = len(sph)
    nodes = _nearest_nodes(sph, _gcsa_icosahedron(gcsa.icno_priors, "priors", gcsa.source))
    class_nodes = gcsa.prior_to_classifier[nodes]
    entries, valid = _node_candidates(gcsa, nodes)
    cand_labels = np.where(valid, gcsa.prior_labels[entries], -1).astype(np.int64)
    probs = np.where(valid, gcsa.prior_probs[entries], 0.0).astype(np.float64)
    score = np.full(probs.shape, -np.inf)
    np.log(probs, out=score, where=probs > 0)

    if method in ("classifier", "gibbs"):
        x = _inputs_matrix(gcsa, n, curv, sulc, adj)
        centries = _class_lookup(
            gcsa, np.broadcast_to(class_nodes[:, None], entries.shape), cand_labels
        )
        score = score + _log_likelihood(gcsa, np.where(valid, centries, -1), x)

    rows = np.arange(n)
    best = np.argmax(score, axis=1)
    lab = np.where(np.isfinite(score[rows, best]), cand_labels[rows, best], -1)
    if method == "gibbs":
        assert adj is not None
        lab = _gibbs_icm(gcsa, lab, entries, valid, cand_labels, score, adj)
    return lab, (cand_labels, score)


def _relabel_cortex(gcsa: Gcsa, lab: NDArray[np.int64], cortex_mask: NDArray[np.bool_],
                    scored: tuple[NDArray[np.int64], NDArray[np.float64]], sph: NDArray[np.float64],
                    adj: sparse.csr_matrix | None) -> None:
    """-1 outside the cortex; inside, unlabelled or non-cortical vertices get their best cortical label."""
    cand_labels, score = scored
    lab[~cortex_mask] = -1
    excluded = _non_cortical_annotations(gcsa)
    redo = cortex_mask & ((lab < 0) | np.isin(lab, excluded))
    if redo.any():
        sc = np.where(np.isin(cand_labels[redo], excluded), -np.inf, score[redo])
        b = np.argmax(sc, axis=1)
        ok = np.isfinite(sc[np.arange(len(b)), b])
        lab[redo] = np.where(ok, cand_labels[redo][np.arange(len(b)), b], -1)
        _fill_from_neighbours(lab, cortex_mask, sph, adj)


def _cortex_mask(cortex: ArrayLike | None, n: int) -> NDArray[np.bool_] | None:
    if cortex is None:
        return None
    c = np.asarray(cortex)
    if c.dtype == bool:
        if c.shape != (n,):
            raise BrainPainterError(f"cortex mask has shape {c.shape}; expected ({n},) booleans.")
        return c.copy()
    if (
        c.ndim != 1
        or not np.issubdtype(c.dtype, np.integer)
        or (c.size and (c.min() < 0 or c.max() >= n))
    ):
        raise BrainPainterError(
            f"cortex must be a boolean mask of shape ({n},) or vertex indices below {n}."
        )
    mask = np.zeros(n, dtype=bool)
    mask[c] = True
    return mask


def _mode_filter(
    gcsa: Gcsa, lab: NDArray[np.int64], adj: sparse.csr_matrix, niter: int
) -> NDArray[np.int64]:
    """``MRISmodeFilterAnnotations`` over the 2-ring (``mris_ca_label -nbrs 2``).

    Each pass, synchronously, gives every vertex the most common label among itself and
    its 2-ring; it keeps its own label when that is among the most common, otherwise
    ties go to the lowest colour-table index.

    Parameters
    ----------
    lab : ndarray of int64, shape (n,)
        Annotation values (-1 = none).
    adj : sparse matrix, shape (n, n)

    Returns
    -------
    ndarray of int64, shape (n,)
    """
    n = len(lab)
    order = np.argsort(gcsa.ctab_index, kind="stable")
    known = gcsa.ctab_annotations[order].astype(np.int64)  # in colour-table index order
    extra = np.setdiff1d(np.unique(lab[lab >= 0]), known)
    values = np.concatenate([known, extra])
    srt = np.argsort(values, kind="stable")
    ring2 = (adj + adj @ adj).tocsr()
    ring2.data[:] = 1.0  # 2-ring membership, self included (FreeSurfer counts self once)
    ring2 = ring2 - sparse.diags(ring2.diagonal()) + sparse.identity(n, format="csr")
    ring2.eliminate_zeros()
    code = np.full(n, -1, dtype=np.int64)
    has = lab >= 0
    code[has] = srt[np.searchsorted(values[srt], lab[has])]
    nvals = len(values)
    for _ in range(niter):
        has = code >= 0
        onehot = sparse.csr_matrix(
            (np.ones(int(has.sum())), (np.flatnonzero(has), code[has])), shape=(n, nvals)
        )
        counts = (ring2 @ onehot).toarray()
        top = counts.max(axis=1)
        own = np.where(has, counts[np.arange(n), np.maximum(code, 0)], -1.0)
        new = np.where((own >= top) | (top == 0), code, np.argmax(counts, axis=1))
        if np.array_equal(new, code):
            break
        code = new
    return np.where(code >= 0, values[np.maximum(code, 0)], -1)


def _non_cortical_annotations(gcsa: Gcsa) -> NDArray[np.int32]:
    mask = np.array([nm.lower() in NON_CORTICAL_NAMES for nm in gcsa.ctab_names], dtype=bool)
    return gcsa.ctab_annotations[mask] if len(mask) else np.zeros(0, np.int32)


def _fill_from_neighbours(
    lab: NDArray[np.int64],
    cortex: NDArray[np.bool_],
    sph: NDArray[np.float64],
    adj: sparse.csr_matrix | None,
) -> None:
    """Give still-unlabelled cortex vertices a label from labelled neighbours, in place.

    With a mesh, labels grow ring by ring (most common labelled neighbour); whatever is
    left (or everything, without a mesh) takes the label of the nearest labelled cortex
    vertex on the sphere.
    """
    if adj is not None:
        for _ in range(1000):
            todo = np.flatnonzero(cortex & (lab < 0))
            if not len(todo):
                return
            sub = adj[todo].tocoo()
            nb_lab = lab[sub.col]
            ok = nb_lab >= 0
            if not ok.any():
                break
            # most common labelled neighbour per row (ties: smallest value)
            pairs = np.unique(
                np.column_stack([sub.row[ok], nb_lab[ok]]), axis=0, return_counts=True
            )
            (r, v), cnt = pairs[0].T, pairs[1]
            order = np.lexsort((v, -cnt, r))
            r, v = r[order], v[order]
            first = np.unique(r, return_index=True)[1]
            lab[todo[r[first]]] = v[first]
    todo = cortex & (lab < 0)
    done = cortex & (lab >= 0)
    if todo.any() and done.any():
        _, idx = cKDTree(sph[done]).query(sph[todo])
        lab[todo] = lab[np.flatnonzero(done)[idx]]


def _gibbs_icm(
    gcsa: Gcsa,
    lab: NDArray[np.int64],
    entries: NDArray[np.int64],
    valid: NDArray[np.bool_],
    cand_labels: NDArray[np.int64],
    unary: NDArray[np.float64],
    adj: sparse.csr_matrix,
    max_iter: int = 50,
) -> NDArray[np.int64]:
    """Iterated conditional modes with the atlas's neighbourhood (Gibbs) priors.

    The energy of label ``L`` at vertex ``v`` is, as in FreeSurfer's
    ``gcsaNbhdGibbsLogLikelihood``, ``unary[v, L]`` plus, for every neighbour ``u``,
    ``log P(label_u | L at v) + log P(L | label_u at u)``. Unlike FreeSurfer, the
    neighbour tables of the two principal-curvature directions are pooled. Vertices
    are updated in batches of an independent set (graph colouring) until nothing
    changes.

    Parameters
    ----------
    lab : ndarray of int64, shape (n,)
        Initial annotation values (-1 = none).
    entries, valid, cand_labels, unary : ndarray, shape (n, K)
        Candidate prior entries, their validity, labels and unary log-scores.
    adj : sparse matrix, shape (n, n)

    Returns
    -------
    ndarray of int64, shape (n,)
    """
    n, kmax = entries.shape
    lookup = _pooled_gibbs(gcsa)
    indptr, indices = adj.indptr, adj.indices
    deg = np.diff(indptr)
    colours = _greedy_colouring(adj)
    lab = lab.copy()
    rows = np.arange(n)

    def current_entry() -> NDArray[np.int64]:
        hit = (cand_labels == lab[:, None]) & valid
        k = np.argmax(hit, axis=1)
        return np.where(hit[rows, k], entries[rows, k], -1)

    cur = current_entry()
    batches = [
        np.flatnonzero((colours == c) & (valid.sum(axis=1) > 1))
        for c in range(int(colours.max()) + 1)
    ]
    for _ in range(max_iter):
        changed = 0
        for verts in batches:
            if not len(verts):
                continue
            dmax = int(deg[verts].max())
            kk = np.arange(dmax)
            nb_ok = kk[None, :] < deg[verts][:, None]
            nb = indices[np.where(nb_ok, indptr[verts][:, None] + kk[None, :], 0)]
            nb_lab = np.where(nb_ok, lab[nb], -1)  # (m, D)
            nb_entry = np.where(nb_ok, cur[nb], -1)  # (m, D)
            energy = unary[verts].copy()
            for k in range(kmax):
                e = np.broadcast_to(entries[verts, k][:, None], nb_lab.shape)
                lk = np.broadcast_to(cand_labels[verts, k][:, None], nb_lab.shape)
                pair = lookup(e, nb_lab) + lookup(nb_entry, lk)
                energy[:, k] += np.where(nb_ok, pair, 0.0).sum(axis=1)
            energy = np.where(valid[verts], energy, -np.inf)
            best = np.argmax(energy, axis=1)
            new = cand_labels[verts, best]
            upd = np.isfinite(energy[np.arange(len(verts)), best]) & (new != lab[verts])
            lab[verts[upd]] = new[upd]
            cur[verts[upd]] = entries[verts[upd], best[upd]]
            changed += int(upd.sum())
        if changed == 0:
            break
    return lab


def _pooled_gibbs(
    gcsa: Gcsa,
) -> Callable[[NDArray[np.int64], NDArray[np.int64]], NDArray[np.float64]]:
    """``log P(neighbour label | prior entry)``, the four neighbour tables pooled.

    Returns a function of two equal-shape arrays (entry index, neighbour label) giving
    the log-probability, or ``BIG_AND_NEGATIVE`` when never observed (or entry < 0).
    """
    m = len(gcsa.prior_labels)
    t = GIBBS_SURFACE_NEIGHBORS
    counts = np.diff(gcsa.gibbs_offsets)
    entry_of = np.repeat(np.arange(m * t, dtype=np.int64) // t, counts)
    table_of = np.repeat(np.arange(m * t, dtype=np.int64) % t, counts)
    weight = gcsa.gibbs_total_nbrs[entry_of, table_of].astype(np.float64)
    mass = gcsa.gibbs_probs.astype(np.float64) * weight
    keys = entry_of * (1 << 25) + gcsa.gibbs_labels.astype(np.int64)
    uk, inv = np.unique(keys, return_inverse=True)
    summed = np.bincount(inv, weights=mass, minlength=len(uk))
    total = gcsa.gibbs_total_nbrs.sum(axis=1).astype(np.float64)
    prob = summed / np.maximum(total[uk >> 25], 1.0)
    logp = np.full(len(uk), BIG_AND_NEGATIVE)
    np.log(prob, out=logp, where=prob > 0)

    def lookup(entry: NDArray[np.int64], label: NDArray[np.int64]) -> NDArray[np.float64]:
        q = entry * (1 << 25) + np.maximum(label, 0)
        pos = np.minimum(np.searchsorted(uk, q), max(len(uk) - 1, 0))
        found = (entry >= 0) & (label >= 0)
        if len(uk):
            found &= uk[pos] == q
            return np.where(found, logp[pos], BIG_AND_NEGATIVE)
        return np.full(q.shape, BIG_AND_NEGATIVE)

    return lookup


def _greedy_colouring(adj: sparse.csr_matrix) -> NDArray[np.int64]:
    """Vertex colouring so that no two neighbours share a colour (greedy, vectorised)."""
    n = adj.shape[0]
    colour = np.full(n, -1, dtype=np.int64)
    rng = np.random.default_rng(0)
    prio = rng.permutation(n)
    c = 0
    remaining = np.ones(n, dtype=bool)
    coo = adj.tocoo()
    while remaining.any():
        # maximal independent set among remaining by local-priority rule (Luby-style)
        cand = remaining.copy()
        chosen = np.zeros(n, dtype=bool)
        while cand.any():
            p = np.where(cand, prio, -1).astype(np.float64)
            nb_max = np.full(n, -1.0)
            np.maximum.at(nb_max, coo.row, p[coo.col])
            win = cand & (p > nb_max)
            chosen |= win
            blocked = np.asarray(adj @ win.astype(np.float64)).ravel() > 0
            cand &= ~win & ~blocked
        colour[chosen] = c
        remaining &= ~chosen
        c += 1
    return colour


def _to_annot(
    gcsa: Gcsa, lab: NDArray[np.int64], keep_unused: bool
) -> tuple[NDArray[np.int32], NDArray[np.int32], list[str]]:
    """Annotation values -> (indices into a colour table, ctab (k, 5), names)."""
    annots = gcsa.ctab_annotations.astype(np.int64)
    if keep_unused:
        keep = np.ones(len(annots), dtype=bool)
    else:
        keep = np.isin(annots, gcsa.used_labels()) | np.isin(annots, lab[lab >= 0])
    ann = annots[keep]
    names = [nm for nm, k in zip(gcsa.ctab_names, keep, strict=True) if k]
    ctab = np.column_stack([gcsa.ctab_rgbt[keep], ann]).astype(np.int32).reshape(-1, 5)
    out = np.full(len(lab), -1, dtype=np.int32)
    if len(ann):
        order = np.argsort(ann, kind="stable")
        pos = np.minimum(np.searchsorted(ann[order], lab), len(ann) - 1)
        found = (lab >= 0) & (ann[order][pos] == lab)
        out[found] = order[pos[found]]
    return out, ctab, names
