"""fsLR (HCP's surface space) brought onto fsaverage: which fsLR mesh a vertex count is, and the resampling.

fsLR 32k (32,492 vertices per hemisphere) and 164k (163,842, the same count
as fsaverage) are resampled onto fsaverage through HCP's fsLR spheres deformed
to fsaverage, as ``wb_command -metric-resample ... ADAP_BARY_AREA`` does:
values by area-weighted (adaptive) barycentric interpolation, labels from the
vertex of largest weight (the nearest). The weights are built once by
``tools/build_fslr_resampling.py`` into ``brainpainter/data/fslr-fsaverage.npz``
(with HCP's notice beside it) and loaded once per resolution and hemisphere.
Vertices outside HCP's cortex (``atlasroi`` = 0, the medial wall) or without a
value in the file give no value: an fsaverage vertex takes the weighted mean
of the finite values it draws on, NaN when it has none.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.maps.resolution import FAMILY, FSLR, N_FSAVERAGE

#: The fsLR meshes that can be resampled (HCP ships no 59k sphere deformed to fsaverage).
RESAMPLED = {32492: "32k", 163842: "164k"}
#: The mesh families a map can be on (a 163,842-vertex map is on either).
SPACES = ("fsaverage", "fsLR")


def check_fslr(n: int, what: str = "map") -> str:
    """The resolution key (``"32k"``/``"164k"``) of an fsLR map of `n` vertices per hemisphere.

    Raises
    ------
    BrainPainterError
        For 59k (no deformed sphere) or a count of no fsLR mesh.
    """
    if n in RESAMPLED:
        return RESAMPLED[n]
    if n == 59292:
        raise BrainPainterError(
            f"{what} is on fsLR 59k (59292 vertices), which brainpainter cannot resample (HCP ships no 59k "
            "sphere deformed to fsaverage); resample it to 32k first: wb_command -metric-resample FILE "
            "L.sphere.59k_fs_LR.surf.gii L.sphere.32k_fs_LR.surf.gii BARYCENTRIC OUT.func.gii.")
    raise BrainPainterError(
        f"{what} has {n} values per hemisphere, which fits no fsLR mesh "
        f"({', '.join(f'{k} {v}' for k, v in FSLR.items())}); give a map of one of these meshes.")


def names_fslr(text: str) -> bool:
    """Whether `text` names fsLR (``fs_LR``, ``fsLR``, BIDS' ``space-fsLR``)."""
    return re.search(r"fs_?lr", text, re.IGNORECASE) is not None


def named_space(texts: Iterable[str]) -> str | None:
    """The mesh family a file's metadata names (`texts`: its values): ``"fsLR"`` or ``"fsaverage"``; None
    where they name neither or both (a provenance of resampling from one to the other)."""
    texts = [str(t) for t in texts]
    fslr = any(names_fslr(t) for t in texts)
    fsaverage = any(re.search("fsaverage", t, re.IGNORECASE) for t in texts)
    return None if fslr == fsaverage else "fsLR" if fslr else "fsaverage"


def decide_space(counts: Mapping[str, int], space: str | None, says_fslr: bool,
                 what: str, declared: str | None = None) -> tuple[str, tuple[str, ...]]:
    """The mesh family of maps with `counts` vertices per hemisphere, and a note when it was a guess.

    32,492 vertices is fsLR 32k (59,292 fsLR 59k, refused: no resampling);
    163,842 is both fsaverage and fsLR 164k: the file's metadata decides where
    it names a family (`declared`, :func:`named_space`; a `space` naming the
    other one is refused), else `space`, else fsLR where the file's name says
    so (`says_fslr`), else fsaverage (with a note).

    Returns
    -------
    (str, tuple of str)
        ``"fsaverage"`` or ``"fsLR"``, and the notes.

    Raises
    ------
    BrainPainterError
        `space` contradicting a count or the file's metadata, fsLR beside fsaverage-family counts, or
        fsLR 59k.
    """
    if space is not None and space not in SPACES:
        raise choice_error("space", space, SPACES)
    only_fslr = sorted({n for n in counts.values() if n in FSLR and n != N_FSAVERAGE})
    if only_fslr:
        if space == "fsaverage":
            raise BrainPainterError(f"{what} has {only_fslr[0]} values per hemisphere: {FSLR[only_fslr[0]]}, "
                                    "not fsaverage; leave out --space (or give --space fsLR).")
        chosen = "fsLR"
    elif N_FSAVERAGE in counts.values():
        if declared is not None and space is not None and space != declared:
            raise BrainPainterError(
                f"{what} says {declared} in its metadata, but --space {space} was given; the file's metadata "
                f"decides where it names the space: leave out --space (or give --space {declared}), or "
                "correct the file's metadata.")
        chosen = declared or space or ("fsLR" if says_fslr else "fsaverage")
    else:
        if space == "fsLR" and counts:
            n = next(iter(counts.values()))
            raise BrainPainterError(f"{what} has {n} values per hemisphere: {FAMILY[n]}, not fsLR; leave out "
                                    "--space (or give --space fsaverage).")
        return "fsaverage", ()
    if chosen == "fsLR":
        for hemi, n in counts.items():
            if n not in FSLR:
                raise BrainPainterError(f"{what} mixes meshes: {hemi} has {n} values per hemisphere ("
                                        f"{FAMILY.get(n, 'no fsLR mesh')}) beside fsLR; give both "
                                        "hemispheres on one mesh.")
            check_fslr(n, f"{what} ({hemi})")
        return "fsLR", ()
    if space is None and declared is None:
        return "fsaverage", (f"{what} has 163842 values per hemisphere, as fsaverage and fsLR 164k have, and "
                             "does not say which: drawn as fsaverage; give --space fsLR if it is fsLR 164k.",)
    return "fsaverage", ()


@cache
def _weights(hemi: str, res: str) -> tuple[Any, NDArray[np.bool_]]:
    """(CSR matrix (163842 x n_fsLR) of weights, fsLR cortex mask (n_fsLR,)), loaded once."""
    from scipy import sparse

    with resources.files("brainpainter").joinpath("data/fslr-fsaverage.npz").open("rb") as fh:
        with np.load(fh) as z:
            indptr, indices = z[f"{hemi}_{res}_indptr"], z[f"{hemi}_{res}_indices"]
            weights = z[f"{hemi}_{res}_weights"].astype(np.float32) / np.float32(65535)
            roi_bits = z[f"{hemi}_{res}_roi"]
    n = {v: k for k, v in RESAMPLED.items()}[res]
    matrix = sparse.csr_matrix((weights, indices, indptr), shape=(N_FSAVERAGE, n))
    return matrix, np.unpackbits(roi_bits)[:n].astype(bool)


def cortex_roi(hemi: str, res: str) -> NDArray[np.bool_]:
    """HCP's cortex of fsLR mesh `res` (``atlasroi``: False on the medial wall), bool (n_fsLR,)."""
    return _weights(hemi, res)[1]


@cache
def _nearest(hemi: str, res: str) -> NDArray[np.int64]:
    """For each fsaverage vertex, the fsLR vertex of largest weight (the nearest), (163842,): its label."""
    matrix, _ = _weights(hemi, res)
    rows = np.repeat(np.arange(N_FSAVERAGE), np.diff(matrix.indptr))
    order = np.lexsort((-matrix.data, rows))  # by row, largest weight first
    return np.asarray(matrix.indices[order[matrix.indptr[:-1]]], np.int64)


def fslr_to_fsaverage(values: NDArray[Any], hemi: str, categorical: bool = False,
                      what: str = "map") -> NDArray[Any]:
    """fsLR values of hemisphere `hemi` resampled onto fsaverage.

    Parameters
    ----------
    values : ndarray, shape (n,) or (k, n)
        One value per fsLR vertex (``n`` 32492 or 163842), NaN = no value.
    hemi : {"lh", "rh"}
    categorical : bool
        Labels: each fsaverage vertex takes the label of its nearest fsLR vertex.

    Returns
    -------
    ndarray of float32, shape (k, 163842)
        NaN where the fsLR map has no value (medial wall, vertices absent from the file).
    """
    v = np.asarray(values, dtype=np.float32)
    v = v[None] if v.ndim == 1 else v
    res = check_fslr(v.shape[1], what)
    matrix, roi = _weights(hemi, res)
    v = np.where(roi, v, np.float32(np.nan))
    if categorical:
        out: NDArray[Any] = v[:, _nearest(hemi, res)]
        return out
    ok = np.isfinite(v)
    total = matrix @ np.where(ok, v, 0.0).T  # (163842, k)
    weight = matrix @ ok.T.astype(np.float32)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(weight > 0, total / weight, np.nan).T.astype(np.float32)
    return out


#: Of the vertices where the two hemispheres' cortex masks differ, the share a map's values must follow
#: the other hemisphere's mask on (and it must follow that mask on all but this share of the rest).
SWAP_AGREE, SWAP_SLACK = 0.9, 0.001


def swapped_hemispheres(values: Mapping[str, NDArray[Any]], names: Mapping[str, str] | None = None
                        ) -> list[str]:
    """Warnings for fsLR maps given as the other hemisphere: where a map has values (finite, not 0) on
    exactly the other hemisphere's cortex (HCP's ``atlasroi``, which differ by 106 of 32,492 vertices), and
    none where only its own has them, it is most likely that hemisphere's (``--lh R.func.gii``).

    Parameters
    ----------
    values : mapping of str to ndarray, (k, n) or (n,)
        fsLR maps by hemisphere (``"lh"``, ``"rh"``).
    names : mapping of str to str, optional
        What each hemisphere's map is, for the messages (default: ``"the map"``).

    Returns
    -------
    list of str
        One line per hemisphere that looks swapped.
    """
    said = []
    for hemi, v in values.items():
        data = np.asarray(v, dtype=np.float64)
        res = RESAMPLED.get(data.shape[-1])
        if res is None or hemi not in ("lh", "rh"):
            continue
        other = "rh" if hemi == "lh" else "lh"
        has = (np.isfinite(data) & (data != 0)).reshape(-1, data.shape[-1]).any(axis=0)
        own, theirs = cortex_roi(hemi, res), cortex_roi(other, res)
        differ = own != theirs
        if not differ.any() or has.all():
            continue
        follows = float(np.mean(has[differ] == theirs[differ]))
        off = float(np.mean(has[~differ] != theirs[~differ]))
        if follows >= SWAP_AGREE and off <= SWAP_SLACK:
            side = {"lh": "left", "rh": "right"}
            said.append(
                f"{(names or {}).get(hemi, 'the map')} given as --{hemi} has values on exactly the "
                f"{side[other]} hemisphere's fsLR cortex "
                f"(HCP's atlasroi: {int(has.sum()):,} vertices, {int((has & ~own).sum())} of them on the "
                f"{side[hemi]} hemisphere's medial wall): it looks like the {side[other]} hemisphere's map; "
                f"give it to --{other} if it is.")
    return said
