"""Region groups: a new atlas whose regions are named groups of another atlas's regions.

The original BrainPainter's "Custom" atlas drew several DK regions as one user
label (a lobe). Here that is a small TOML file::

    [atlas]
    base = "dk"                  # required: any installed or user atlas, or a combination of a
                                 # cortical and volumetric atlases ("schaefer400_7n+tian_s2"; then
                                 # [groups] may be left out)
    name = "lobes"               # optional (default: the file name); 'atlas add NAME' overrides it
    title = "Lobes"              # optional; also description, citation
    ungrouped = "keep"           # "keep" (default): regions in no group stay regions of their own;
                                 # "drop": they are not regions (cortex drawn like the medial wall)

    [groups]
    # Two-sided group: hemisphere-free region names -> Left-frontal and Right-frontal
    frontal = ["superiorfrontal", "rostralmiddlefrontal", "caudalmiddlefrontal"]
    # One hemisphere: a Left- or Right- group name; members are names or keys of that side
    "Left-language" = ["parsopercularis", "parstriangularis", "Left-superiortemporal"]
    # A table sets the colour (default: a colour of matplotlib's tab10/tab20 per group)
    basal-ganglia = { regions = ["Caudate", "Putamen", "Pallidum"], color = "#3060c0" }

Structures without a side (``Brain-Stem``) form a group of their own name.
Names are matched case-insensitively against the base atlas's region names,
keys and aliases. Every error names the file, the group and the region, with
the nearest region names; a region may be in one group only.

The atlas made carries the group -> member mapping (``Atlas.members``), draws
with the base atlas's label set, and colours every member of a group with the
group's value.
"""

from __future__ import annotations

import difflib
import tomllib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from brainpainter.atlas.model import HEMI_PREFIX, Atlas, Region
from brainpainter.color.rgb import to_rgb
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.io.files import read_input
from brainpainter.io.rawtable import has_control

MAX_CONFIG_BYTES = 1024 * 1024  # a region-group config is a few KB
_LOADING: set[str] = set()  # names of group atlases being built (to catch cycles)
ATLAS_KEYS = ("base", "name", "title", "description", "citation", "ungrouped")
UNGROUPED = ("keep", "drop")
_SIDES = {"left-": "lh", "right-": "rh"}


def read_atlas_config(path: str | Path, name: str | None = None, *,
                      get_base: Callable[[str], Atlas]) -> Atlas:
    """Read a region-group TOML file and build its atlas.

    Parameters
    ----------
    path : path-like
    name : str, optional
        Atlas name (default: ``[atlas] name``, else the file name without suffix).
    get_base : callable
        ``get_base(name) -> Atlas`` looks up the base atlas
        (:func:`brainpainter.atlas.registry.get_atlas`; :func:`brainpainter.atlas.registry.load_atlas_config`
        passes it).

    Raises
    ------
    BrainPainterError
        Unreadable TOML, unknown keys, unknown base atlas or region, a region
        in two groups; one line naming the file.
    """
    path = Path(path).expanduser()
    raw = read_input(path, "atlas config", MAX_CONFIG_BYTES,
                     hint="give the path of a TOML file with [atlas] and [groups] (see docs/atlases.md)")
    try:
        config = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BrainPainterError(f"{path} is not valid TOML: {' '.join(str(exc).split())[:200]}; see "
                                "docs/atlases.md for the format") from None
    meta = config.get("atlas", {})
    if not isinstance(meta, dict) or not isinstance(config.get("groups", {}), dict):
        raise _fail(str(path), "[atlas] and [groups] must be tables, e.g. [atlas] base = \"dk\"; see "
                               "docs/atlases.md")
    given = meta.get("name")
    if given is not None and not isinstance(given, str):
        raise _fail(str(path), f"[atlas] name must be a text; {given!r} was given")
    return atlas_from_config(config, source=str(path), name=name or given or path.name.split(".")[0],
                             get_base=get_base)


def _cycle(base: str) -> str:
    return (f"[atlas] base {base!r} leads back to this atlas (a cycle of region-group atlases); base it on "
            "an atlas with label maps, e.g. dk")


def _fail(source: str, msg: str) -> BrainPainterError:
    return BrainPainterError(f"{source}: {msg}")


def _nearest(value: str, pool: list[str]) -> str:
    lower = {p.lower(): p for p in pool}
    hits = difflib.get_close_matches(value.lower(), list(lower), n=3, cutoff=0.6)
    return f" Did you mean {', '.join(repr(lower[h]) for h in hits)}?" if hits else ""


def _palette(n: int, avoid: Sequence[tuple[int, int, int]] = ()) -> list[tuple[int, int, int]]:
    """`n` group colours from matplotlib's tab10 (tab20 beyond 10), skipping ones close to `avoid`."""
    import matplotlib

    names = ("tab10", "tab20") if n <= 10 else ("tab20", "tab20b", "tab20c")
    pool = list(dict.fromkeys(tuple(round(255 * c) for c in matplotlib.colormaps[m](i)[:3])
                              for m in names for i in range(matplotlib.colormaps[m].N)))
    def distinct(c: tuple[int, ...]) -> bool:
        return all(sum((a - b) ** 2 for a, b in zip(c, k, strict=True)) > 60**2 for k in avoid)

    far = [c for c in pool if distinct(c)]
    ordered = far + [c for c in pool if c not in far]
    return [ordered[i % len(ordered)] for i in range(n)]  # type: ignore[misc]


Group = tuple[str, str, str, tuple[int, int, int] | None, list[Region]]
"""A parsed group: (region key, hemi, core name, colour or None, member regions of the base atlas)."""


def atlas_from_config(config: dict[str, Any], source: str, name: str, *,
                      get_base: Callable[[str], Atlas]) -> Atlas:
    """Build a group atlas from a parsed config (see the module docstring for the schema).

    Parameters
    ----------
    config : dict
        The parsed TOML (``[atlas]`` and ``[groups]`` tables).
    source : str
        Where it came from, for messages.
    name : str
        Name of the atlas being defined.
    get_base : callable
        ``get_base(name) -> Atlas`` looks up the base atlas.
    """
    meta, groups = _check_tables(config, source, name)
    base = _load_base(str(meta["base"]), source, name, get_base)
    ungrouped = meta.get("ungrouped", "keep")
    if ungrouped not in UNGROUPED:
        raise _fail(source, str(choice_error("[atlas] ungrouped", ungrouped, UNGROUPED)))
    if not groups and "+" not in str(meta["base"]):
        raise _fail(source, "[groups] is empty; add e.g. frontal = [\"superiorfrontal\", ...]")
    lookup = _Lookup(base, source)
    parsed: list[Group] = []
    for gname, value in groups.items():
        parsed.extend(_parse_group(gname, value, lookup))
    kept = _check_owners(parsed, base, ungrouped, source)
    return _group_atlas(parsed, kept, base, meta, source, name, ungrouped)


def _check_tables(config: dict[str, Any], source: str, name: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``[atlas]`` and ``[groups]`` tables, checked up to (not including) loading the base."""
    extra = sorted(set(config) - {"atlas", "groups"})
    if extra:
        raise _fail(source, f"unknown table {extra[0]!r}; a config has [atlas] and [groups]")
    meta = config.get("atlas", {})
    groups = config.get("groups", {})
    if not isinstance(meta, dict) or not isinstance(groups, dict):
        raise _fail(source, "[atlas] and [groups] must be tables")
    bad = sorted(set(meta) - set(ATLAS_KEYS))
    if bad:
        raise _fail(source, f"[atlas] has the unknown key {bad[0]!r}; allowed: {list(ATLAS_KEYS)}")
    if "base" not in meta:
        raise _fail(source, '[atlas] needs base = "ATLAS", the atlas whose regions are grouped (e.g. "dk")')
    if not isinstance(meta["base"], str):
        raise _fail(source, f'[atlas] base must be an atlas name such as "dk"; {meta["base"]!r} was given')
    if meta["base"].strip().lower() == str(name).strip().lower():
        raise _fail(source, f"[atlas] base {meta['base']!r} is the atlas being defined; a region-group atlas "
                            "groups the regions of another atlas (e.g. base = \"dk\")")
    return meta, groups


def _load_base(base_name: str, source: str, name: str, get_base: Callable[[str], Atlas]) -> Atlas:
    """The base atlas, refusing a cycle of group atlases."""
    if base_name.strip().lower() in _LOADING:
        raise _fail(source, _cycle(base_name))
    _LOADING.add(str(name).strip().lower())
    try:
        return get_base(base_name)  # "schaefer400_7n+tian_s2" combines atlases
    except BrainPainterError as exc:
        raise _fail(source, f"[atlas] base: {str(exc)[:300]}") from None
    except RecursionError:
        raise _fail(source, _cycle(base_name)) from None
    finally:
        _LOADING.discard(str(name).strip().lower())


class _Lookup:
    """The base atlas's regions by key (``Left-insula``) and by hemisphere-free name (``insula``)."""

    def __init__(self, base: Atlas, source: str) -> None:
        self.base, self.source = base, source
        self.by_key = {r.key.lower(): r for r in base.regions}
        self.by_name: dict[str, list[Region]] = {}
        for r in base.regions:
            self.by_name.setdefault(r.name.lower(), []).append(r)
            for a in r.aliases:
                if a.lower() in self.by_key:
                    continue
                if a.lower().startswith(("ctx-lh-", "ctx-rh-", "left-", "right-")):
                    self.by_key.setdefault(a.lower(), r)
                else:
                    self.by_name.setdefault(a.lower(), []).append(r)
        self.names = sorted({r.name for r in base.regions})

    def unknown(self, group: str, member: str, pool: list[str]) -> BrainPainterError:
        return _fail(self.source, f"group {group!r} names {member!r}, which is not a region of atlas "
                                  f"{self.base.name!r}.{_nearest(member, pool)} "
                                  f"See 'brainpainter atlas show {self.base.name}'.")

    def two_sided(self, gname: str, m: str) -> list[Region]:
        """Regions a member of a group without a side names."""
        low = m.strip().lower()
        if low in self.by_key and self.by_key[low].hemi != "bilateral" and low not in self.by_name:
            raise _fail(self.source, f"group {gname!r} lists {m!r}, a region of one hemisphere; a "
                                     f"two-sided group takes hemisphere-free names "
                                     f"({self.by_key[low].name!r}), or name the group 'Left-{gname}' / "
                                     f"'Right-{gname}'")
        hits = self.by_name.get(low) or ([self.by_key[low]] if low in self.by_key else [])
        if not hits:
            raise self.unknown(gname, m, self.names)
        return hits

    def one_sided(self, gname: str, m: str, side: str) -> list[Region]:
        """Regions a member of a ``Left-``/``Right-`` group names."""
        low = m.strip().lower()
        where = "left" if side == "lh" else "right"
        if low in self.by_key:
            if self.by_key[low].hemi != side:
                raise _fail(self.source,
                            f"group {gname!r} lists {m!r}, which is not in the {where} hemisphere")
            return [self.by_key[low]]
        if low in self.by_name:
            hits = [r for r in self.by_name[low] if r.hemi == side]
            if not hits:
                raise _fail(self.source, f"group {gname!r} lists {m!r}, which has no {where}-hemisphere "
                                         f"region in atlas {self.base.name!r}")
            return hits
        raise self.unknown(gname, m, [r.key for r in self.base.regions if r.hemi == side] + self.names)


def _group_value(gname: str, value: Any, source: str) -> tuple[list[str], tuple[int, int, int] | None]:
    """A group's member names and colour (a list, or a table with ``regions`` and ``color``)."""
    color = None
    if isinstance(value, dict):
        bad = sorted(set(value) - {"regions", "color"})
        if bad or "regions" not in value:
            raise _fail(source, f"group {gname!r} must be a list of regions or a table with 'regions' "
                                f"(and optionally 'color'); {bad[0] if bad else 'regions'!r} is wrong")
        if "color" in value:
            try:
                color = tuple(round(255 * c) for c in to_rgb(value["color"]))
            except BrainPainterError as exc:
                raise _fail(source, f"group {gname!r}: {exc}") from None
        value = value["regions"]
    if not isinstance(value, list) or not value or not all(isinstance(m, str) for m in value):
        raise _fail(source, f"group {gname!r} must list region names, e.g. {gname} = [\"insula\"]")
    if not gname.strip() or any(c in gname for c in "\t\n\r,|") or has_control(gname):
        raise _fail(source, f"group name {gname[:40]!r} must be non-empty without tabs, commas, '|' or "
                            "control characters")
    return value, color  # type: ignore[return-value]


def _parse_group(gname: str, value: Any, lookup: _Lookup) -> list[Group]:
    """One ``[groups]`` entry as one group per hemisphere it has members in."""
    source = lookup.source
    names, color = _group_value(gname, value, source)
    side = next((h for p, h in _SIDES.items() if gname.lower().startswith(p) and len(gname) > len(p)), None)
    core = gname.split("-", 1)[1] if side else gname
    members: dict[str, list[Region]] = {"lh": [], "rh": [], "bilateral": []}
    for m in dict.fromkeys(names):
        hits = lookup.two_sided(gname, m) if side is None else lookup.one_sided(gname, m, side)
        for r in hits:
            if r not in members[r.hemi]:
                members[r.hemi].append(r)
    if members["bilateral"] and (members["lh"] or members["rh"]):
        raise _fail(source, f"group {gname!r} mixes structures without a side "
                            f"({members['bilateral'][0].key!r}) with one-hemisphere regions; put them "
                            "in separate groups")
    return [(HEMI_PREFIX[hemi] + core, hemi, core, color, members[hemi])
            for hemi in ("lh", "rh", "bilateral") if members[hemi]]


def _check_owners(parsed: list[Group], base: Atlas, ungrouped: str, source: str) -> list[Region]:
    """A region in one group only; group keys unique and not shadowing kept regions. Returns the kept."""
    owner: dict[str, str] = {}
    for key, _, _, _, regs in parsed:
        for r in regs:
            if r.key in owner and owner[r.key] != key:
                raise _fail(source, f"region {r.key!r} is in groups {owner[r.key]!r} and {key!r}; a region "
                                    "can be in one group only")
            owner[r.key] = key
    keys = [p[0] for p in parsed]
    dup = next((k for k in keys if keys.count(k) > 1), None)
    if dup:
        raise _fail(source, f"two groups make the region {dup!r}; give them different names")
    kept = [r for r in base.regions if r.key not in owner] if ungrouped == "keep" else []
    clash = next((r.key for r in kept if r.key in keys), None)
    if clash:
        raise _fail(source, f"group {clash!r} has the name of the region {clash!r} of {base.name!r}, which "
                            "is in no group; add that region to the group or rename the group")
    return kept


def _group_atlas(parsed: list[Group], kept: list[Region], base: Atlas, meta: dict[str, Any], source: str,
                 name: str, ungrouped: str) -> Atlas:
    """The atlas of the groups (coloured from a palette where no colour was given) and the kept regions."""
    cores = list(dict.fromkeys(p[2] for p in parsed if p[3] is None))
    avoid = [r.color for r in kept if r.kind == "cortical"]
    palette = dict(zip(cores, _palette(len(cores), avoid), strict=True)) if cores else {}
    regions: list[Region] = []
    members_out: list[tuple[str, tuple[str, ...]]] = []
    for i, (key, hemi, core, color, regs) in enumerate(parsed, start=1):
        kind = "cortical" if any(r.kind == "cortical" for r in regs) else "subcortical"
        offset = {"lh": 1000, "rh": 2000, "bilateral": 0}[hemi] if kind == "cortical" else 0
        regions.append(Region(offset + i, core, hemi, kind, color or palette[core]))
        drawn = tuple(k for r in regs for k in base.member_keys(r.key))
        members_out.append((key, drawn))
    regions.extend(kept)
    members_out.extend((r.key, base.member_keys(r.key)) for r in kept if base.member_keys(r.key) != (r.key,))
    n_groups = len({p[2] for p in parsed})
    return Atlas(
        name=name,
        title=str(meta.get("title") or f"{base.title}: {n_groups} region groups"),
        template_labels=base.template_labels,
        regions=tuple(regions),
        description=str(meta.get("description") or
                        f"Groups of {base.name} regions ({source}); ungrouped regions: {ungrouped}."),
        citation=str(meta.get("citation") or base.citation),
        label_dir=base.label_dir,
        members=tuple(members_out),
        volume_dirs=base.volume_dirs,
        sources=tuple((k, v) for k, v in base.sources if k in {r.key for r in regions}),
    )
