"""Read region-value tables as researchers have them, and resolve them against an atlas.

Inputs: table files (CSV, TSV, ``;``-separated with decimal commas, .xlsx;
see :mod:`brainpainter.io.readers`), bytes, pandas DataFrames and dicts, or a
list of these (e.g. the ``lh`` and ``rh`` files of ``aparcstats2table``),
merged by image name. Layouts: wide, long and transposed (see
:mod:`brainpainter.table.shape`). Names: any spelling known to the atlas's
alias table (see :mod:`brainpainter.table.names`); the atlas itself is
inferred from the names when not given.

:func:`inspect_table` reads everything it can and lists every problem (what
``brainpainter check`` shows); :func:`read_table` is the same but raises the
first problem as a one-line :class:`~brainpainter.errors.BrainPainterError`.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.errors import BrainPainterError, NoRegionColumnError
from brainpainter.io.output import file_key, same_file_phrase
from brainpainter.io.rawtable import MAX_BYTES, RawTable
from brainpainter.io.readers import read_raw
from brainpainter.table.cells import is_text
from brainpainter.table.columns import (
    CellProblem,
    NameReport,
    Part,
    read_part,
)
from brainpainter.table.names import (
    IGNORED,
    REGION,
    UNMATCHED,
    AtlasGuess,
    NameResolver,
    closest_each,
    infer_atlas,
)
from brainpainter.table.shape import IMAGE_COLUMN, IMAGE_COLUMN_NAMES, SAMPLE_ROWS, TableShape, detect_shape

__all__ = ["IMAGE_COLUMN", "MAX_BYTES", "CellProblem", "NameReport", "RegionTable", "inspect_table",
           "read_table"]

DEFAULT_ATLAS = "dk"


@dataclass(frozen=True)
class RegionTable:
    """Values per image and region, resolved against one atlas.

    Attributes
    ----------
    images : tuple of str
        Image names, unique, in input order.
    regions : tuple of str
        Region keys of the atlas that have a value column, in input order.
    values : ndarray of float, shape (n_images, n_regions)
        NaN marks an empty cell.
    atlas : Atlas
    names : tuple of NameReport
        Every region-like name of the input and how it was understood.
    source : str
        Where the table came from (paths joined with ", ", or "DataFrame").
    shapes : tuple of TableShape
        Layout of each input.
    formats : tuple of str
        File format of each input.
    atlas_guess : AtlasGuess or None
        How the atlas was inferred; None when it was given.
    problems : tuple of CellProblem
        Cells that are not numbers or not finite (their values are NaN here).
    errors : tuple of str
        Problems that stop rendering (first the cell problems, then others
        such as unmatched names under ``strict``); empty when the table is fine.
    notes : tuple of str
        Other remarks for the report (decimal commas read, images missing from an input).
    sources : tuple of str
        Where each input came from.
    """

    images: tuple[str, ...]
    regions: tuple[str, ...]
    values: NDArray[Any]
    atlas: Atlas
    names: tuple[NameReport, ...] = ()
    source: str = ""
    shapes: tuple[TableShape, ...] = ()
    formats: tuple[str, ...] = ()
    atlas_guess: AtlasGuess | None = None
    problems: tuple[CellProblem, ...] = ()
    errors: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)
    sources: tuple[str, ...] = ()

    def __repr__(self) -> str:
        """One short line (the values are many)."""
        return (f"<RegionTable {self.source!r}: {len(self.images)} image(s) x {len(self.regions)} region(s) "
                f"of atlas {self.atlas.name!r}>")

    @property
    def columns(self) -> dict[str, tuple[str, ...]]:
        """Every region-like input name and the region keys it set (empty tuple: not a region)."""
        return {n.name: n.keys for n in self.names}

    @property
    def unmatched(self) -> list[str]:
        """Names that match no region of the atlas and no known non-region name."""
        return [n.name for n in self.names if n.status == UNMATCHED]

    @property
    def ignored(self) -> dict[str, str]:
        """Names recognised as not regions (``eTIV``, ``lh_MeanThickness_thickness``) and why."""
        return {n.name: n.reason for n in self.names if n.status == IGNORED}

    @property
    def absent(self) -> list[str]:
        """Atlas regions with no value column in the input."""
        have = set(self.regions)
        return [k for k in self.atlas.keys if k not in have]

    @property
    def naming(self) -> dict[str, int]:
        """Naming conventions recognised among the region names, with counts."""
        return dict(Counter(n.naming for n in self.names if n.status == REGION).most_common())

    def row(self, i: int) -> dict[str, float]:
        """``{region key: value}`` of image `i` (NaN for empty cells)."""
        return dict(zip(self.regions, self.values[i].tolist(), strict=True))

    def raise_errors(self) -> RegionTable:
        """Raise the first error as a BrainPainterError; return self when there is none."""
        if self.errors:
            raise BrainPainterError(self.errors[0])
        return self

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary for reports and manifests."""
        finite = self.values[np.isfinite(self.values)]
        return {
            "source": self.source,
            "inputs": [{"source": s, "format": f, "shape": sh.to_dict()}
                       for s, f, sh in zip(self.sources or (self.source,), self.formats, self.shapes,
                                           strict=False)],
            "atlas": self.atlas.name,
            "atlas_inferred": self.atlas_guess is not None,
            "atlas_reason": self.atlas_guess.reason if self.atlas_guess else "given",
            "naming": self.naming,
            "n_images": len(self.images),
            "n_regions_matched": len(self.regions),
            "n_regions_in_atlas": len(self.atlas),
            "unmatched_columns": self.unmatched,
            "ignored_columns": self.ignored,
            "regions_without_value": self.absent,
            "n_empty_cells": int(np.isnan(self.values).sum()),
            "value_range": [float(finite.min()), float(finite.max())] if finite.size else None,
            "notes": list(self.notes),
        }

    def summary_line(self) -> str:
        """The summary in one line (printed by ``render``)."""
        return summary_line(self.summary())


def summary_line(s: dict[str, Any]) -> str:
    """One line from :meth:`RegionTable.summary`'s dict."""
    rng = s["value_range"]
    rng_text = f"values {rng[0]:g}..{rng[1]:g}" if rng else "no values"
    tracts = s.get("tract_values")  # a run's bundle values or profiles (rendering.run)
    if tracts:
        trng = tracts["value_range"]
        rng_text += (f"; tract values {trng[0]:g}..{trng[1]:g}" if trng else "; no tract values") + (
            f" on {len(tracts['bundles'])} bundle(s)")
    shapes = "; ".join(dict.fromkeys(
        i["shape"]["kind"] + (f" ({i['shape']['flavour']})" if i["shape"]["flavour"] else "")
        for i in s.get("inputs", [])))
    atlas = f"atlas {s['atlas']}" + (" (inferred)" if s.get("atlas_inferred") else "")
    return (
        f"{shapes or 'table'}, {atlas}: {s['n_images']} image(s), {s['n_regions_matched']}/"
        f"{s['n_regions_in_atlas']} regions with values, {len(s['unmatched_columns'])} unmatched, "
        f"{len(s.get('ignored_columns', {}))} not regions, {s['n_empty_cells']} empty cell(s), {rng_text}"
    )


# -- atlas ---------------------------------------------------------------------------
def installed_atlases() -> list[Atlas]:
    """Installed atlases that load, ``dk`` first (the historical default)."""
    from brainpainter.atlas import registry
    out: list[Atlas] = []
    names = registry.atlases.names()
    for name in sorted(names, key=lambda n: (n != DEFAULT_ATLAS, n)):
        try:
            atlas = registry.atlases.get(name)
        except BrainPainterError:
            continue
        if all(atlas is not a for a in out):
            out.append(atlas)
    return out


def _candidate_names(raw: RawTable) -> list[str]:
    names = dict.fromkeys(raw.header)
    for j in range(len(raw.header)):
        for row in raw.rows[:SAMPLE_ROWS]:
            cell = row[j]
            if is_text(cell):
                names[str(cell).strip()] = None
                if len(names) > 20_000:
                    return list(names)
    return list(names)


# -- public ---------------------------------------------------------------------------
def inspect_table(data: Any, atlas: Atlas | str | None = None, *, image_column: str | None = None,
                  value: str | None = None, region_column: str | None = None,
                  strict: bool = False) -> RegionTable:
    """Read a table and resolve it, collecting every problem instead of stopping at the first.

    Parameters and layout rules as in :func:`read_table`. Errors that leave
    nothing to report (unreadable file, no region names, duplicate regions,
    bad image names) are raised; cells that are not numbers or not finite,
    columns without any value and (with `strict`) unmatched names are listed
    in ``table.errors``.

    Returns
    -------
    RegionTable
    """
    from brainpainter.atlas.registry import get_atlas

    inputs = list(data) if isinstance(data, list | tuple) else [data]
    if not inputs:
        raise BrainPainterError("no input was given; give at least one table.")
    raws = [read_raw(d) for d in inputs]
    guess: AtlasGuess | None = None
    if atlas is None:
        candidates = installed_atlases()
        names = [n for raw in raws for n in _candidate_names(raw)]
        guess = infer_atlas(names, candidates)
        if guess is None:
            resolvers = [NameResolver.for_atlas(a) for a in candidates]

            def suggest(name: object) -> list[str]:
                return next((hit for r in resolvers if (hit := r.suggest(name))), [])

            shown = closest_each([h for raw in raws for h in raw.header
                                  if str(h).strip() and str(h).lower() not in IMAGE_COLUMN_NAMES], suggest)
            raise NoRegionColumnError(
                f"{', '.join(r.source for r in raws)}: no column name or value names a region of any "
                f"installed atlas ({', '.join(a.name for a in candidates)}); the columns: {shown}. Use "
                "names like 'Left-insula' or 'lh_insula_thickness' (see 'brainpainter atlas show dk')."
            )
        atlas = guess.atlas
    elif isinstance(atlas, str):
        atlas = get_atlas(atlas)
    resolver = NameResolver.for_atlas(atlas)
    parts = []
    for raw in raws:
        try:
            shape = detect_shape(raw, resolver, image_column=image_column, region_column=region_column,
                                 value_column=value)
        except NoRegionColumnError as exc:
            if guess is None:
                other = infer_atlas(_candidate_names(raw), installed_atlases())
                if other is not None and other.atlas.name != atlas.name:
                    raise NoRegionColumnError(
                        f"{exc} The names fit atlas {other.atlas.name!r}: give --atlas {other.atlas.name}."
                    ) from None
            raise
        part = read_part(raw, shape, resolver)
        part.shape = _with_flavour(shape, part.names, raw)
        parts.append(part)
    table = _merge(parts, atlas, guess)
    _check_file_names(table)
    if guess is None and table.unmatched:  # --atlas destrieux on a DK table: its cortex silently grey
        table = _replace(table, notes=(*table.notes, *_better_atlas(raws, table)))
    errors = [p.message for p in table.problems]
    if not table.regions:
        errors.append(_no_regions_error(table, resolver))
    if strict and table.unmatched:
        errors.append(
            f"{table.source}: {len(table.unmatched)} name(s) match no {atlas.name} region: "
            f"{resolver.closest_each(table.unmatched)}; rename them or drop --strict."
        )
    return _replace(table, errors=tuple(errors))


def _better_atlas(raws: list[RawTable], table: RegionTable) -> list[str]:
    """A note where the names of a table read with the atlas given fit another installed atlas better."""
    other = infer_atlas([n for raw in raws for n in _candidate_names(raw)], installed_atlases())
    if other is None or other.atlas.name == table.atlas.name:
        return []
    here = other.scores.get(table.atlas.name, len(table.regions))
    there = other.scores[other.atlas.name]
    if there <= here:
        return []
    return [f"the names fit atlas {other.atlas.name!r} better ({there} of its regions against {here} of "
            f"{table.atlas.name!r}): give --atlas {other.atlas.name}"]


def _check_file_names(table: RegionTable) -> None:
    """Refuse image names that become the same file name (ignoring case, as macOS and Windows do)."""
    from brainpainter.io.output import file_key, safe_name

    seen: dict[str, str] = {}
    for name in table.images:
        other = seen.setdefault(file_key(safe_name(name)), name)
        if other != name:
            raise BrainPainterError(
                f"{table.source}: image names {other!r} and {name!r} become the same file name "
                f"({safe_name(name)!r}, ignoring case as macOS and Windows do) after removing unsafe "
                "characters; make the image names differ in letters or digits."
            )


def _no_regions_error(table: RegionTable, resolver: NameResolver) -> str:
    names = f": {resolver.closest_each(table.unmatched)}" if table.unmatched else ""
    return (f"{table.source}: no name matches a {table.atlas.name} region{names}; use names like "
            f"{table.atlas.keys[:2]}.")


def _replace(table: RegionTable, **changes: Any) -> RegionTable:
    return dataclasses.replace(table, **changes)


def _with_flavour(shape: TableShape, names: list[NameReport], raw: RawTable) -> TableShape:
    if shape.flavour:
        return shape
    first = raw.header[0].lower() if raw.header else ""
    naming = Counter(n.naming for n in names if n.status == REGION).most_common(1)
    top = naming[0][0] if naming else ""
    if first.startswith("measure:"):
        flavour = "FreeSurfer asegstats2table"
    elif shape.kind == "wide" and top == "FreeSurfer stats table":
        flavour = "FreeSurfer aparcstats2table"
    elif top:
        flavour = f"{top} names"
    else:
        flavour = ""
    return dataclasses.replace(shape, flavour=flavour)


def _merge(parts: list[Part], atlas: Atlas, guess: AtlasGuess | None) -> RegionTable:
    notes = [n for p in parts for n in p.notes]
    if len(parts) == 1:
        p = parts[0]
        images = p.images
        keys = list(p.columns)
        values = np.column_stack([p.columns[k][0] for k in keys]) if keys else np.empty((len(images), 0))
    else:
        numbered = {p.numbered for p in parts}
        if len(numbered) > 1:
            named = next(p for p in parts if not p.numbered)
            bare = next(p for p in parts if p.numbered)
            raise BrainPainterError(
                f"input {named.source!r} names its images (column {named.shape.image_column!r}) but "
                f"{bare.source!r} has no image-name column; merging needs names in both (give "
                "--image-column)."
            )
        if numbered == {True} and len({len(p.images) for p in parts}) > 1:
            raise BrainPainterError(
                "the inputs have no image-name column and different numbers of rows "
                f"({[len(p.images) for p in parts]}); add an image-name column to merge them by name."
            )
        images = list(dict.fromkeys(i for p in parts for i in p.images))
        folded: dict[str, str] = {}
        for name in images:
            other = folded.setdefault(file_key(name), name)
            if other != name:
                src = {n: p.source for p in parts for n in p.images}
                raise BrainPainterError(
                    f"image names {same_file_phrase(other, name)} ({src[other]}, {src[name]}), so they would "
                    "be two half-empty images; spell the image names the same in every input."
                )
        pos = {name: k for k, name in enumerate(images)}
        owner: dict[str, Part] = {}
        keys, cols = [], []
        for p in parts:
            index = np.array([pos[i] for i in p.images], dtype=int)
            for key, (vals, name) in p.columns.items():
                if key in owner:
                    raise BrainPainterError(
                        f"inputs {owner[key].source!r} ({owner[key].columns[key][1]!r}) and {p.source!r} "
                        f"({name!r}) both give region {key!r}; give each region in one input only."
                    )
                owner[key] = p
                col = np.full(len(images), np.nan)
                col[index] = vals
                keys.append(key)
                cols.append(col)
            missing = [i for i in images if i not in set(p.images)]
            if missing:
                notes.append(f"{len(missing)} image(s) not in {p.source} (e.g. {missing[0]!r}): its regions "
                             "are empty for them")
        values = np.column_stack(cols) if cols else np.empty((len(images), 0))
    return RegionTable(
        images=tuple(images),
        regions=tuple(keys),
        values=values.astype(float).reshape(len(images), len(keys)),
        atlas=atlas,
        names=tuple(n for p in parts for n in p.names),
        source=", ".join(p.source for p in parts),
        sources=tuple(p.source for p in parts),
        shapes=tuple(p.shape for p in parts),
        formats=tuple(p.format for p in parts),
        atlas_guess=guess,
        problems=tuple(pr for p in parts for pr in p.problems),
        notes=tuple(notes),
    )


def read_table(data: Any, atlas: Atlas | str | None = None, *, image_column: str | None = None,
               value: str | None = None, region_column: str | None = None, strict: bool = False,
               ) -> RegionTable:
    """Read a region-value table and resolve its names against an atlas.

    Parameters
    ----------
    data : path-like, bytes, binary file, pandas.DataFrame, pandas.Series, dict, or a list of these
        A table file (CSV, TSV, ``;``-separated with decimal commas, .xlsx),
        a DataFrame, ``{region: value or [values]}``, ``{image: {region: value}}``;
        a list is merged by image name (e.g. the ``lh`` and ``rh`` tables of
        ``aparcstats2table``).
    atlas : Atlas or str, optional
        Inferred from the names when not given (``table.atlas_guess`` says how).
    image_column : str, optional
        Column with the image names. Default: ``Image-name-unique``, a
        FreeSurfer first column, a DataFrame index or a ``subject``-like
        column; otherwise rows are numbered ``1, 2, ...``.
    value : str, optional
        Long tables: the column with the values (needed when several columns are numeric).
    region_column : str, optional
        Long tables: the column with region names (auto-detected when unambiguous).
    strict : bool
        Names that match no region (and are not known non-region measures) are an error.

    Returns
    -------
    RegionTable

    Raises
    ------
    BrainPainterError
        On the first problem, as one line saying what was given and what to do.
    """
    return inspect_table(data, atlas, image_column=image_column, value=value, region_column=region_column,
                         strict=strict).raise_errors()
