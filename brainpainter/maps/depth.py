"""Depth sampling: a subject-space volume read between that subject's white and pial surfaces.

Like nilearn's ``vol_to_surf(..., inner_mesh=...)`` (kind ``"depth"``): each vertex gets
``n_depths`` points evenly spaced from its white-surface position (depth 0) to its
pial-surface position (depth 1); the volume is sampled at each and the samples combine into
one value per vertex (mean, max, or the most frequent value of a label volume).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error

Depth = Literal["mean", "max", "nearest"]
DEPTHS = ("mean", "max", "nearest")
HEMI_NAMES = {"lh": "lh", "rh": "rh", "left": "lh", "right": "rh"}

SurfaceLike = str | os.PathLike[str] | NDArray[Any] | tuple[NDArray[Any], NDArray[Any]]


def read_surface(surface: SurfaceLike, what: str) -> NDArray[np.float64]:
    """Vertex positions of one surface, in the world (scanner RAS) millimetres of the volume.

    Parameters
    ----------
    surface : path, ndarray of shape (n, 3), or (vertices (n, 3), faces (m, 3))
        A FreeSurfer surface file (``lh.white``; its tkr-RAS positions are moved to scanner RAS
        with the ``cras`` of the volume it was made from, stored in the file), a GIfTI surface
        (``.surf.gii``, taken as scanner RAS, as fMRIPrep writes them), or the positions.
    what : str
        Which surface, for messages (``"white lh"``).

    Returns
    -------
    ndarray, shape (n, 3)
    """
    if isinstance(surface, tuple):
        surface = surface[0]
    if isinstance(surface, (str, os.PathLike)):
        return _read_surface_file(Path(surface), what)
    xyz = np.asarray(surface, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or len(xyz) == 0 or not np.isfinite(xyz).all():
        raise BrainPainterError(
            f"the {what} surface must be vertex positions of shape (n, 3) with finite values; "
            f"an array of shape {xyz.shape} was given.")
    return xyz


def _read_surface_file(path: Path, what: str) -> NDArray[np.float64]:
    from nibabel.freesurfer.io import read_geometry

    from brainpainter.io.gifti import read_gifti

    if not path.is_file():
        raise BrainPainterError(f"the {what} surface {path} does not exist; give a FreeSurfer surface "
                                "(surf/lh.white) or a GIfTI .surf.gii file.")
    try:
        if path.name.endswith((".gii", ".gii.gz")):
            img: Any = read_gifti(path, what=f"{what} surface")
            arrays = img.get_arrays_from_intent("NIFTI_INTENT_POINTSET") or img.darrays[:1]
            return read_surface(np.asarray(arrays[0].data), what)
        coords, _, meta = read_geometry(path, read_metadata=True)  # type: ignore[no-untyped-call]
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel raises many types for a file that is not a surface
        raise BrainPainterError(f"cannot read the {what} surface {path} ({type(exc).__name__}: {exc}); "
                                "give a FreeSurfer surface (surf/lh.white) or a GIfTI .surf.gii.") from None
    cras = np.asarray(meta.get("cras", np.zeros(3)), dtype=np.float64)
    return read_surface(np.asarray(coords, dtype=np.float64) + cras, what)


def surface_pairs(white: dict[str, SurfaceLike], pial: dict[str, SurfaceLike]
                  ) -> dict[str, tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """``{"lh": (white (n, 3), pial (n, 3)), ...}`` from the two dictionaries of surfaces."""
    w = {_hemi(k): v for k, v in white.items()}
    p = {_hemi(k): v for k, v in pial.items()}
    if set(w) != set(p) or not w:
        raise BrainPainterError(
            f"white and pial must name the same hemispheres ('lh' and/or 'rh'); {sorted(w)} and "
            f"{sorted(p)} were given.")
    pairs = {}
    for hemi in sorted(w):
        inner, outer = read_surface(w[hemi], f"white {hemi}"), read_surface(p[hemi], f"pial {hemi}")
        if inner.shape != outer.shape:
            raise BrainPainterError(
                f"the white and pial {hemi} surfaces must have the same vertices; they have "
                f"{len(inner)} and {len(outer)}. Give the white and pial surfaces of one subject.")
        pairs[hemi] = (inner, outer)
    return pairs


def _hemi(key: str) -> str:
    if key not in HEMI_NAMES:
        raise choice_error("a hemisphere", key, HEMI_NAMES)
    return HEMI_NAMES[key]


def depth_points(white: NDArray[np.float64], pial: NDArray[np.float64], n_depths: int
                 ) -> NDArray[np.float64]:
    """Points between white and pial, shape (n_depths, n, 3); depth 0 = white, 1 = pial."""
    if n_depths < 1:
        raise BrainPainterError(f"n_depths must be 1 or more; {n_depths} was given.")
    t = np.linspace(0.0, 1.0, n_depths) if n_depths > 1 else np.array([0.5])
    return white[None] + t[:, None, None] * (pial - white)[None]


def sample_points(white: dict[str, SurfaceLike], pial: dict[str, SurfaceLike], depth: str, n_depths: int
                  ) -> tuple[dict[str, NDArray[np.float64]], dict[str, tuple[int, int]]]:
    """`n_depths` points per vertex from white to pial, per hemisphere, shape (n * n_depths, 3),
    and ``(n, n_depths)``; `depth` checked."""
    if depth not in DEPTHS:
        raise choice_error("depth", depth, DEPTHS)
    pairs = surface_pairs(white, pial)
    return ({hemi: depth_points(w, p, n_depths).reshape(-1, 3) for hemi, (w, p) in pairs.items()},
            {hemi: (len(w), n_depths) for hemi, (w, _) in pairs.items()})


def combine(samples: NDArray[np.float32], depth: str) -> NDArray[np.float32]:
    """One value per vertex from the samples at several depths.

    Parameters
    ----------
    samples : ndarray, shape (n_depths, n)
        NaN where a point lies outside the volume or on a NaN voxel.
    depth : {"mean", "max", "nearest"}
        ``"mean"`` and ``"max"`` of the finite samples; ``"nearest"`` the most frequent value
        (for label volumes sampled at the nearest voxel; ties go to the depth nearest white).

    Returns
    -------
    ndarray, shape (n,)
        NaN where no sample is finite.
    """
    if depth not in DEPTHS:
        raise choice_error("depth", depth, DEPTHS)
    finite = np.isfinite(samples)
    count = finite.sum(axis=0)
    if depth == "mean":
        total = np.where(finite, samples, 0).sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            out = (total / count).astype(np.float32)
    elif depth == "max":
        out = np.where(finite, samples, -np.inf).max(axis=0).astype(np.float32)
    else:
        votes = (samples[:, None, :] == samples[None, :, :]).sum(axis=1)   # (n_depths, n)
        out = samples[np.argmax(votes, axis=0), np.arange(samples.shape[1])].astype(np.float32)
    out[count == 0] = np.nan
    result: NDArray[np.float32] = out
    return result
