"""Which atlas region each row of a matrix is: by its name, or by the atlas's documented order.

A matrix with names has them matched as a region table's columns are
(:class:`brainpainter.table.names.NameResolver`: ``Left-precentral``,
``ctx-lh-precentral``, ``7Networks_LH_Vis_1``, ...). A matrix without names
follows the atlas's *node order*: its cortical regions, left hemisphere then
right, each in the atlas's table order (for Schaefer 2018 its label order
1..N); or, for a matrix with a row per region of the atlas, the cortical
regions so and then the subcortical ones in table order. ``brainpainter atlas
show NAME`` prints this order.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.connectome.sizes import atlases_taking, better_fit, taking_text
from brainpainter.errors import BrainPainterError
from brainpainter.table.names import NameResolver


def node_order(atlas: Atlas) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The atlas's node order for matrices without names.

    Returns
    -------
    cortical : tuple of str
        Region keys of the cortex, left hemisphere then right, each in table order.
    every : tuple of str
        `cortical`, then the subcortical (and volume) regions in table order.
    """
    cortical = tuple(r.key for hemi in ("lh", "rh") for r in atlas.cortical(hemi))
    return cortical, cortical + tuple(r.key for r in atlas.subcortical())


def describe_order(atlas: Atlas) -> str:
    """One sentence saying which regions, in which order, a matrix without names stands for."""
    cortical, every = node_order(atlas)
    if not cortical or len(cortical) == len(every):
        return (f"a connectome matrix without names has its {len(every)} regions as rows, in the order "
                "listed here")
    return (f"a connectome matrix without names has as rows its {len(cortical)} cortical regions (left "
            f"hemisphere, then right, in the order listed here) or all {len(every)} regions (those, then "
            "the subcortical ones as listed)")


def ordered_keys(atlas: Atlas, weights: NDArray[np.float64], source: str, atlas_given: bool = True,
                 place: Callable[[Atlas, tuple[str, ...]], NDArray[np.float64]] | None = None
                 ) -> tuple[str, ...]:
    """Region keys of the rows of a matrix without names (:func:`node_order`).

    Where other atlases take as many rows, warns naming them and the order assumed (and, where the
    weights follow another atlas's networks clearly better, that one: :mod:`brainpainter.connectome.sizes`).

    Parameters
    ----------
    atlas : Atlas
    weights : ndarray, (N, N)
    source : str
        The matrix, for messages.
    atlas_given : bool
        False: `atlas` is the default one, not chosen by the user; the messages then do not name it.
    place : callable, optional
        ``place(atlas, keys)``: the regions' centroids, (N, 3); given, the other atlases of N rows are
        compared with `atlas` (:func:`brainpainter.connectome.sizes.better_fit`).

    Raises
    ------
    BrainPainterError
        N is neither the number of cortical regions nor of all regions (naming the atlases that take N).
    """
    n = len(weights)
    cortical, every = node_order(atlas)
    installed, elsewhere = atlases_taking(n, node_order)
    taking = taking_text(n, installed, elsewhere)
    keys = next((k for k in (cortical, every) if k and len(k) == n), None)
    if keys is None or not atlas_given:
        if atlas_given:
            counts = sorted({len(cortical), len(every)} - {0})
            said = (f"atlas {atlas.name!r} takes a matrix without names of {' or '.join(map(str, counts))} "
                    f"rows ('brainpainter atlas show {atlas.name}' lists their order); {taking}")
        else:
            said = f"no --atlas was given; {taking}"
        if keys is None or not installed or installed != [atlas.name]:
            raise BrainPainterError(
                f"connectome matrix {source!r} has {n} rows and no names; {said}. Give the node names in the "
                "matrix's first row or column, a nodes file, or the atlas whose node order it follows "
                "(--atlas).")
    others = [name for name in installed + elsewhere if name != atlas.name]
    better = None if place is None else better_fit(weights, atlas, installed, node_order, place)
    if better is not None:
        warnings.warn(
            f"connectome matrix {source!r} has no names; its {n} rows were placed in the node order of atlas "
            f"{atlas.name!r}, but its weights follow the places of {better[0]!r}'s regions far better "
            f"(correlation of weight with nearness {better[1]:.2f} vs {better[2]:.2f}): give --atlas "
            f"{better[0]} if it was made in that order, or the node names.", UserWarning, stacklevel=3)
    elif others or not atlas_given:
        warnings.warn(
            f"connectome matrix {source!r} has no names{'' if atlas_given else ' and no --atlas was given'}; "
            f"its {n} rows were placed in the node order of atlas {atlas.name!r} "
            f"({_order_text(atlas, keys)}); "
            f"{taking}: give the node names, or --atlas naming the atlas whose order it follows.",
            UserWarning, stacklevel=3)
    return keys


def _order_text(atlas: Atlas, keys: tuple[str, ...]) -> str:
    cortical, _ = node_order(atlas)
    if keys == cortical:
        return "its cortical regions, left hemisphere then right, in its label order"
    return "its cortical regions, left then right, then the subcortical ones, in its label order"


def matched_keys(names: Sequence[str], atlas: Atlas, source: str) -> tuple[str, ...]:
    """The region key each of `names` names, as a region table's columns are matched.

    Raises
    ------
    BrainPainterError
        A name that matches no region (with the closest region keys), a bare name that means both
        hemispheres, or two names of one region.
    """
    resolver = NameResolver.for_atlas(atlas)
    keys: list[str] = []
    unmatched: list[str] = []
    seen: dict[str, str] = {}
    for name in names:
        hit = resolver.lookup(name)
        if len(hit.keys) != 1 or hit.status != "region":
            unmatched.append(name)
            continue
        key = hit.keys[0]
        if key in seen:
            raise BrainPainterError(
                f"connectome matrix {source!r}: nodes {seen[key]!r} and {name!r} both name region {key!r} of "
                f"atlas {atlas.name!r}; give each node once.")
        seen[key] = name
        keys.append(key)
    if unmatched:
        both = resolver.lookup(unmatched[0])
        if len(both.keys) > 1:
            why = (f"{unmatched[0]!r} means both {list(both.keys)}; give the hemisphere (e.g. "
                   f"{both.keys[0]!r})")
        else:
            why = resolver.closest_each(unmatched)
        raise BrainPainterError(
            f"connectome matrix {source!r}: {len(unmatched)} of {len(names)} node name(s) name no single "
            f"region of atlas {atlas.name!r}: {why}. Rename them ('brainpainter atlas show "
            f"{atlas.name}' lists the regions), give --atlas the matrix's atlas, or give a nodes file.")
    return tuple(keys)
