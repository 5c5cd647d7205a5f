"""Resolve input column names to atlas region keys.

One alias table per atlas, case-insensitive. This first pass knows the
BrainPainter column names (``Left-insula``), FreeSurfer look-up-table names
(``ctx-lh-insula``, ``ctx_lh_G_and_S_frontomargin``, ``Left-Hippocampus``),
hemisphere-prefixed names (``lh_insula``, ``lh.insula``) and each region's own
aliases from its look-up table (``Left-Thalamus-Proper``).
"""

from __future__ import annotations

from dataclasses import dataclass

from brainpainter.atlas import Atlas, Region
from brainpainter.errors import nearest

_SIDE = {"lh": ("Left-", "ctx-lh-", "ctx_lh_", "lh_", "lh.", "lh-", "L_"),
         "rh": ("Right-", "ctx-rh-", "ctx_rh_", "rh_", "rh.", "rh-", "R_")}


def _variants(region: Region) -> set[str]:
    names = {region.name, *region.aliases}
    if region.hemi == "bilateral":
        return names
    return {prefix + n for n in names for prefix in _SIDE[region.hemi]}


@dataclass(frozen=True)
class NameResolver:
    """Case-insensitive lookup from any known spelling to a region key."""

    atlas: Atlas
    table: dict[str, str]

    @classmethod
    def for_atlas(cls, atlas: Atlas) -> NameResolver:
        table: dict[str, str] = {}
        for region in atlas.regions:
            for v in _variants(region):
                table.setdefault(v.lower(), region.key)
            table[region.key.lower()] = region.key
        return cls(atlas, table)

    def resolve(self, column: str) -> str | None:
        """The region key for `column`, or None."""
        return self.table.get(str(column).strip().lower())

    def suggest(self, column: str, n: int = 3) -> list[str]:
        """Closest region keys to an unmatched column name."""
        return nearest(str(column), self.atlas.keys, n=n)
