"""Resolve input names to atlas region keys: one alias table per atlas.

Every atlas gets one case-insensitive table from any known spelling to the
region key(s) it names. The table is built from data, not typed here:

* the atlas's own look-up table: each region's ``name`` and ``aliases``
  (``regions.tsv``, e.g. ``ctx-lh-insula``);
* ``brainpainter/data/region_conventions.tsv``: synonyms shared by naming
  conventions (ENIGMA's ``hippo``/``thal``/..., FreeSurfer 6's
  ``Thalamus-Proper``) and names that are *not* regions and are set aside
  rather than reported as unmatched (summary measures such as ``eTIV`` or
  ``lh_MeanThickness_thickness``, structures without a mesh such as
  ``unknown`` or ``Left-vessel``);
* the hemisphere conventions below, applied to every hemisphere-free name.

Spellings covered, e.g. for the left insula and hippocampus:

==============================  =========================================
BrainPainter                     ``Left-insula``, ``Left-Hippocampus``
BrainPainter 2019 (both sides)   ``insula`` (sets ``Left-`` and ``Right-``)
FreeSurfer look-up table         ``ctx-lh-insula``, ``ctx_lh_G_cuneus``,
                                 ``Left-Thalamus-Proper`` (FreeSurfer 6)
FreeSurfer stats tables          ``lh_insula_thickness``, ``lh_insula_area``
ENIGMA                           ``L_insula``, ``L_insula_thickavg``,
                                 ``Lhippo``, ``Rthal``, ``LLatVent``
ggseg                            ``lh_insula``
atlas label list (Schaefer)      ``7Networks_LH_Vis_1`` (a ``_LH_`` token)
==============================  =========================================
"""

from __future__ import annotations

import csv
import difflib
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

from brainpainter.atlas.model import Atlas, Region

# Hemisphere affixes: (text, "prefix" or "suffix", naming convention). Matched case-insensitively.
# The right hemisphere's are the left's mirrored (Left -> Right, lh -> rh, L -> R).
_LEFT_AFFIXES: tuple[tuple[str, str, str], ...] = (
    ("Left-", "prefix", "BrainPainter"), ("Left_", "prefix", "other"), ("Left ", "prefix", "other"),
    ("ctx-lh-", "prefix", "FreeSurfer look-up table"), ("ctx_lh_", "prefix", "FreeSurfer look-up table"),
    ("lh_", "prefix", "ggseg"), ("lh.", "prefix", "other"), ("lh-", "prefix", "other"),
    ("L_", "prefix", "ENIGMA"), ("L-", "prefix", "other"), ("L.", "prefix", "other"),
    ("_lh", "suffix", "other"), ("-lh", "suffix", "other"), (".lh", "suffix", "other"),
    ("_L", "suffix", "other"), ("-L", "suffix", "other"), ("_left", "suffix", "other"),
)


def _mirrored(text: str) -> str:
    return text.replace("Left", "Right").replace("left", "right").replace("lh", "rh").replace("L", "R")


_AFFIXES: dict[str, tuple[tuple[str, str, str], ...]] = {
    "lh": _LEFT_AFFIXES,
    "rh": tuple((_mirrored(text), where, naming) for text, where, naming in _LEFT_AFFIXES),
}
# A hemisphere inside a name, between underscores: Schaefer 2018's 7Networks_LH_Vis_1.
_HEMI_TOKEN = re.compile(r"_([LR]H)_", re.IGNORECASE)
# ENIGMA's subcortical codes carry the hemisphere as a bare letter: Lhippo, RLatVent.
_ENIGMA_LETTER = {"lh": "L", "rh": "R"}

# Measure suffixes of FreeSurfer stats tables (aparcstats2table) and ENIGMA tables.
MEASURE_SUFFIXES: dict[str, str] = {
    "_thicknessstd": "FreeSurfer stats table", "_thickness": "FreeSurfer stats table",
    "_area": "FreeSurfer stats table", "_volume": "FreeSurfer stats table",
    "_meancurv": "FreeSurfer stats table", "_gauscurv": "FreeSurfer stats table",
    "_foldind": "FreeSurfer stats table", "_curvind": "FreeSurfer stats table",
    "_thickavg": "ENIGMA", "_surfavg": "ENIGMA", "_grayvol": "ENIGMA",
}
_BARE = "BrainPainter 2019 (bare name, both hemispheres)"

REGION, IGNORED, UNMATCHED = "region", "ignored", "unmatched"


def normalise(name: object) -> str:
    """Lower-case `name`, trim and collapse white space, spell ``&`` as ``_and_``."""
    return " ".join(str(name).split()).lower().replace("&", "_and_")


@dataclass(frozen=True)
class Convention:
    """One row of ``region_conventions.tsv``."""

    name: str
    means: str
    kind: str  # "alias", "summary" or "not-drawn"
    source: str


@cache
def conventions() -> tuple[Convention, ...]:
    """Shared synonyms and known non-region names (``data/region_conventions.tsv``)."""
    text = (resources.files("brainpainter") / "data" / "region_conventions.tsv").read_text(encoding="utf-8")
    rows = csv.DictReader(text.splitlines(), delimiter="\t")
    return tuple(Convention(r["name"], r["means"] or "", r["kind"], r["source"]) for r in rows)


@dataclass(frozen=True)
class Resolution:
    """How one input name was understood.

    Attributes
    ----------
    name : str
        The name as given (a column header, or a value of a region column).
    status : {"region", "ignored", "unmatched"}
    keys : tuple of str
        Region keys the name sets: one, two for a bare lateral name
        (``insula`` sets ``Left-insula`` and ``Right-insula``), none otherwise.
    naming : str
        Convention recognised (``"FreeSurfer stats table"``, ``"ENIGMA"``, ...).
    reason : str
        For ignored names: why it is not a region (``"summary measure (FreeSurfer)"``).
    source : str
        Input the name came from (set by the table reader).
    """

    name: str
    status: str
    keys: tuple[str, ...] = ()
    naming: str = ""
    reason: str = ""
    source: str = ""


@dataclass(frozen=True)
class _Entry:
    status: str
    keys: tuple[str, ...]
    naming: str
    rank: int  # lower wins when two spellings collide
    reason: str = ""


def _split_affix(name: str) -> tuple[str | None, str]:
    """(hemi, hemisphere-free rest) of a normalised name; (None, name) without a hemisphere affix."""
    for hemi, affixes in _AFFIXES.items():
        for text, where, _ in affixes:
            t = text.lower()
            if where == "prefix" and name.startswith(t) and len(name) > len(t):
                return hemi, name[len(t):]
            if where == "suffix" and name.endswith(t) and len(name) > len(t):
                return hemi, name[: -len(t)]
    return None, name


@dataclass(frozen=True)
class NameResolver:
    """Case-insensitive lookup from any known spelling to region keys of one atlas.

    Build it with :meth:`for_atlas` (cached per atlas object).
    """

    atlas: Atlas
    table: dict[str, _Entry] = field(repr=False)
    hemi_free: dict[str, dict[str, str]] = field(repr=False)  # normalised name -> {hemi: key}

    @classmethod
    def for_atlas(cls, atlas: Atlas) -> NameResolver:
        return _resolver(atlas)

    # -- lookup ------------------------------------------------------------
    def lookup(self, name: object) -> Resolution:
        """Resolve one name; never raises."""
        text = str(name)
        n = normalise(text)
        entry = self.table.get(n)
        measure = None
        if entry is None:
            for suffix, convention in MEASURE_SUFFIXES.items():
                if n.endswith(suffix) and len(n) > len(suffix):
                    entry = self.table.get(n[: -len(suffix)])
                    if entry is not None:
                        measure = convention
                        break
        if entry is None:
            return Resolution(text, UNMATCHED)
        naming = entry.naming
        if measure is not None:
            naming = "ENIGMA" if measure == "ENIGMA" or naming == "ENIGMA" else measure
        return Resolution(text, entry.status, entry.keys, naming, entry.reason)

    def resolve(self, name: object) -> str | None:
        """The single region key `name` names, or None (unmatched, ignored or a bare two-sided name)."""
        r = self.lookup(name)
        return r.keys[0] if r.status == REGION and len(r.keys) == 1 else None

    def suggest(self, name: object, n: int = 3) -> list[str]:
        """Closest region keys to an unmatched name (hemisphere kept when it has one)."""
        norm = normalise(name)
        for suffix in MEASURE_SUFFIXES:
            if norm.endswith(suffix) and len(norm) > len(suffix):
                norm = norm[: -len(suffix)]
                break
        hemi, core = _split_affix(norm)
        out: list[str] = []
        if hemi is not None:
            for hit in difflib.get_close_matches(core, list(self.hemi_free), n=n, cutoff=0.6):
                key = self.hemi_free[hit].get(hemi)
                if key and key not in out:
                    out.append(key)
        if not out:
            lower = {k.lower(): k for k in self.atlas.keys}
            names = {k: v for k, v in self.hemi_free.items() if "bilateral" in v}
            pool = {**lower, **{k: v["bilateral"] for k, v in names.items()}}
            out = [pool[h] for h in difflib.get_close_matches(norm, list(pool), n=n, cutoff=0.5)]
        return out[:n]

    def closest_each(self, names: Sequence[object], limit: int = 6) -> str:
        """Each of `names` with its closest region key, for a message:
        ``'Left-insular' (did you mean 'Left-insula'?), 'foo', ... and 3 more``."""
        return closest_each(names, self.suggest, limit)


def closest_each(names: Sequence[object], suggest: Callable[[object], list[str]], limit: int = 6) -> str:
    """Each of `names` (up to `limit`) with the closest match `suggest` gives it, where one is close."""
    shown = []
    for name in names[:limit]:
        close = suggest(name)
        shown.append(f"{str(name)!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    more = f" and {len(names) - limit} more" if len(names) > limit else ""
    return ", ".join(shown) + more


def _embedded_hemi(name: str) -> str | None:
    """Hemisphere written inside a name as a ``_LH_`` / ``_RH_`` token (``7Networks_LH_Vis_1``), or None."""
    hit = _HEMI_TOKEN.search(name)
    return None if hit is None else hit.group(1).lower()


def _hemi_free_names(region: Region, extra: dict[str, list[tuple[str, str]]]) -> tuple[
        list[tuple[str, str, int]], list[tuple[str, str]]]:
    """Hemisphere-free names of `region` as (name, naming, rank) and full aliases as (name, naming)."""
    free: list[tuple[str, str, int]] = [(region.name, "BrainPainter", 1)]
    full: list[tuple[str, str]] = []
    for alias in region.aliases:
        hemi, _ = _split_affix(normalise(alias))
        if hemi is not None:
            full.append((alias, "FreeSurfer look-up table"))
        elif _embedded_hemi(alias) == region.hemi:
            full.append((alias, "atlas label list"))  # Schaefer/CBIG, nilearn: 7Networks_LH_Vis_1
        else:
            free.append((alias, "FreeSurfer look-up table", 2))
    for alias, source in extra.get(normalise(region.name), []):
        free.append((alias, source, 3))
    return free, full


_RESOLVERS: dict[int, tuple[Atlas, NameResolver]] = {}


def _resolver(atlas: Atlas) -> NameResolver:
    hit = _RESOLVERS.get(id(atlas))
    if hit is None or hit[0] is not atlas:
        hit = (atlas, _build(atlas))
        _RESOLVERS[id(atlas)] = hit
    return hit[1]


def _build(atlas: Atlas) -> NameResolver:
    extra: dict[str, list[tuple[str, str]]] = {}
    for c in conventions():
        if c.kind == "alias":
            extra.setdefault(normalise(c.means), []).append((c.name, c.source))
    table: dict[str, _Entry] = {}

    def put(name: str, entry: _Entry) -> None:
        n = normalise(name)
        old = table.get(n)
        if old is None or entry.rank < old.rank:
            table[n] = entry

    # Names that are not regions first; any region spelling outranks them.
    for c in conventions():
        if c.kind == "alias":
            continue
        reason = ("summary measure, not a region" if c.kind == "summary"
                  else "structure without a mesh in the templates") + f" ({c.source})"
        entry = _Entry(IGNORED, (), c.source, 9, reason)
        put(c.name, entry)
        for affixes in _AFFIXES.values():
            for text, where, _ in affixes:
                put(text + c.name if where == "prefix" else c.name + text, entry)

    bare: dict[str, list[str]] = {}
    hemi_free: dict[str, dict[str, str]] = {}
    for region in atlas.regions:
        put(region.key, _Entry(REGION, (region.key,), "BrainPainter", 0))
        free, full = _hemi_free_names(region, extra)
        for alias, naming in full:
            put(alias, _Entry(REGION, (region.key,), naming, 1))
        for name, naming, rank in free:
            hemi_free.setdefault(normalise(name), {})[region.hemi] = region.key
            if region.hemi == "bilateral":
                put(name, _Entry(REGION, (region.key,), naming if rank > 1 else "BrainPainter", rank))
                continue
            for text, where, convention in _AFFIXES[region.hemi]:
                spelled = text + name if where == "prefix" else name + text
                label = convention if naming == "BrainPainter" else (
                    naming if convention in ("BrainPainter", "other") else convention)
                put(spelled, _Entry(REGION, (region.key,), label, rank))
            if naming == "ENIGMA":
                put(_ENIGMA_LETTER[region.hemi] + name, _Entry(REGION, (region.key,), "ENIGMA", rank))
            bare.setdefault(normalise(name), []).append(region.key)
    for name, keys in bare.items():
        unique = tuple(dict.fromkeys(keys))
        put(name, _Entry(REGION, unique, _BARE, 5))
    return NameResolver(atlas, table, hemi_free)


def resolve_names(names: Iterable[object], atlas: Atlas) -> list[Resolution]:
    """Resolve many names against `atlas` (see :class:`NameResolver`)."""
    resolver = NameResolver.for_atlas(atlas)
    return [resolver.lookup(n) for n in names]


@dataclass(frozen=True)
class AtlasGuess:
    """Which atlas a set of names belongs to.

    Attributes
    ----------
    atlas : Atlas
        The chosen atlas.
    scores : dict of str to int
        Distinct regions each installed atlas recognises.
    reason : str
        One sentence for reports.
    """

    atlas: Atlas
    scores: dict[str, int]
    reason: str


def infer_atlas(names: Sequence[object], atlases: Sequence[Atlas]) -> AtlasGuess | None:
    """Pick the atlas whose regions the names cover best; None when no atlas knows any name.

    The atlas recognising the most distinct regions wins. On a tie, an atlas
    whose cortical regions are all present wins (a full DKT table also
    resolves in DK, but only DKT is complete); otherwise the first in
    `atlases` (the default order puts ``dk`` first).
    """
    best: tuple[Any, ...] | None = None
    scores: dict[str, int] = {}
    for order, atlas in enumerate(atlases):
        keys: set[str] = set()
        for r in resolve_names(names, atlas):
            keys.update(r.keys)
        cortical = {r.key for r in atlas.cortical()}
        complete = bool(cortical) and cortical <= keys
        scores[atlas.name] = len(keys)
        rank = (len(keys), complete, -order)
        if keys and (best is None or rank > best[0]):
            best = (rank, atlas, complete, bool(keys & cortical))
    if best is None:
        return None
    (_, atlas, complete, has_cortex) = best
    top = best[0][0]
    tied = [n for n, s in scores.items() if s == top and n != atlas.name]
    if not has_cortex and tied:
        reason = f"only subcortical names, which every atlas has; {atlas.name!r} used"
    elif tied:
        reason = (f"{top} regions recognised, as in {tied}; {atlas.name!r} chosen because "
                  + ("all its cortical regions are present" if complete else "it comes first"))
    else:
        reason = f"{top} regions recognised, more than in any other atlas"
    return AtlasGuess(atlas, scores, reason)
