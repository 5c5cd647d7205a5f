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

from collections.abc import Sequence

from brainpainter.atlas.model import Atlas
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


def ordered_keys(atlas: Atlas, n: int, source: str) -> tuple[str, ...]:
    """Region keys of the `n` rows of a matrix without names (:func:`node_order`).

    Raises
    ------
    BrainPainterError
        `n` is neither the number of cortical regions nor of all regions.
    """
    cortical, every = node_order(atlas)
    for keys in (cortical, every):
        if keys and len(keys) == n:
            return keys
    counts = sorted({len(cortical), len(every)} - {0})
    raise BrainPainterError(
        f"connectome matrix {source!r} has {n} rows and no names; atlas {atlas.name!r} takes a matrix "
        f"without names of {' or '.join(map(str, counts))} rows ('brainpainter atlas show {atlas.name}' "
        "lists their order). Give the node names in the matrix's first row or column, a nodes file, or "
        "another atlas.")


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
        first = unmatched[0]
        both = resolver.lookup(first)
        if len(both.keys) > 1:
            why = f"means both {list(both.keys)}; give the hemisphere (e.g. {both.keys[0]!r})"
        else:
            close = resolver.suggest(first)
            why = "matches no region" + (f" (did you mean {close[0]!r}?)" if close else "")
        raise BrainPainterError(
            f"connectome matrix {source!r}: {len(unmatched)} of {len(names)} node name(s) name no single "
            f"region of atlas {atlas.name!r}: {first!r} {why}. Rename them ('brainpainter atlas show "
            f"{atlas.name}' lists the regions), give --atlas the matrix's atlas, or give a nodes file.")
    return tuple(keys)
