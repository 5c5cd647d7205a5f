"""The ``brainpainter check`` report: how a table was read, without rendering.

:func:`check_report` gathers, for a :class:`~brainpainter.table.region_table.RegionTable`
read exactly as ``render`` reads it: each input's format and shape, the atlas
(and how it was inferred), every name and the region(s) it set or why not
(with the closest known names), atlas regions without a value, cells that are
not numbers or not finite, and the value range against the colour scale.
:func:`format_report` prints it for people; ``--json`` prints the dict.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.table.names import REGION, UNMATCHED, NameResolver, closest_each
from brainpainter.table.region_table import RegionTable, installed_atlases

MAX_SUGGESTED = 50
MAX_LISTED = 24


def _closest(name: str, table: RegionTable) -> dict[str, Any]:
    resolver = NameResolver.for_atlas(table.atlas)
    elsewhere = []
    for atlas in installed_atlases():
        if atlas.name == table.atlas.name:
            continue
        r = NameResolver.for_atlas(atlas).lookup(name)
        if r.status == REGION:
            elsewhere.append(atlas.name)
    return {"closest": resolver.suggest(name), "region_of_atlas": elsewhere}


def colour_bar(scale: Any) -> dict[str, Any]:
    """A colour bar of `scale` for a page: ``ramp`` (32 hex colours, vmin to vmax) and ``ticks``."""
    from brainpainter.color.rgb import to_hex
    from brainpainter.color.scale import between, fraction

    ramp = scale(between(scale.vmin, scale.vmax, np.linspace(0.0, 1.0, 32)))
    ticks = np.asarray(scale.ticks(), dtype=float)
    at = np.clip(fraction(ticks, scale.vmin, scale.vmax), 0.0, 1.0)
    labels = ["0" if v == 0 else f"{v:.3g}" for v in ticks]
    return {"ramp": [to_hex(c) for c in ramp],
            "ticks": [{"at": round(float(a), 4), "label": t} for a, t in zip(at, labels, strict=True)]}


def _scale_check(values: NDArray[Any], scale_options: dict[str, Any]) -> dict[str, Any]:
    from brainpainter.color.scale import make_scale

    scale = make_scale(data=values, **scale_options)
    finite = values[np.isfinite(values)]
    below = int((finite < scale.vmin).sum())
    above = int((finite > scale.vmax).sum())
    hints = []
    if below or above:
        hints.append(f"{below} value(s) below vmin {scale.vmin:g} and {above} above vmax {scale.vmax:g} are "
                     "drawn in the end colours; set --vmin/--vmax to the data range")
    if finite.size and finite.min() < 0 < finite.max() and scale.center is None:
        hints.append("values have both signs: a diverging scale (--cmap RdBu_r --center 0) may read better")
    return {
        "range": [float(finite.min()), float(finite.max())] if finite.size else None,
        "scale": {"name": scale.name, "vmin": scale.vmin, "vmax": scale.vmax, "center": scale.center,
                  **colour_bar(scale)},
        "n_below_vmin": below,
        "n_above_vmax": above,
        "hints": hints,
    }


def check_report(table: RegionTable, **scale_options: Any) -> dict[str, Any]:
    """Everything ``brainpainter check`` reports about `table`, JSON-ready.

    Parameters
    ----------
    table : RegionTable
        From :func:`brainpainter.table.region_table.inspect_table`.
    **scale_options
        ``gradient``, ``cmap``, ``vmin``, ``vmax``, ``center`` as for render.
    """
    summary = table.summary()
    origin = dict(table.atlas.sources)
    names = []
    n_suggested = 0
    for n in table.names:
        entry: dict[str, Any] = {"source": n.source, "name": n.name, "status": n.status,
                                 "regions": list(n.keys), "naming": n.naming, "reason": n.reason}
        if origin and n.keys:  # a combined atlas: which of its atlases the name matched
            entry["atlas"] = origin.get(n.keys[0], table.atlas.name)
        if n.status == UNMATCHED and n_suggested < MAX_SUGGESTED:
            entry.update(_closest(n.name, table))
            n_suggested += 1
        names.append(entry)
    guess = table.atlas_guess
    scale_error = None
    try:
        values = _scale_check(table.values, scale_options)
    except Exception as exc:  # a bad scale option is reported, the table check still stands
        from brainpainter.errors import BrainPainterError

        if not isinstance(exc, BrainPainterError):
            raise
        scale_error = str(exc)
        values = {"range": summary["value_range"], "scale": None, "n_below_vmin": 0, "n_above_vmax": 0,
                  "hints": []}
    errors = list(table.errors) + ([scale_error] if scale_error else [])
    return {
        "ok": not errors,
        "summary": table.summary_line(),
        "inputs": summary["inputs"],
        "atlas": {"name": table.atlas.name, "inferred": guess is not None,
                  "reason": guess.reason if guess else "given with --atlas",
                  "scores": guess.scores if guess else {}},
        "naming": summary["naming"],
        "n_images": summary["n_images"],
        "images": list(table.images[:20]),
        "names": names,
        "n_regions_with_value": summary["n_regions_matched"],
        "n_regions_in_atlas": summary["n_regions_in_atlas"],
        "unmatched": summary["unmatched_columns"],
        "ignored": summary["ignored_columns"],
        "regions_without_value": summary["regions_without_value"],
        "cells": {"n_empty": summary["n_empty_cells"],
                  "problems": [{"source": p.source, "where": p.where, "column": p.column, "value": p.value,
                                "problem": p.problem} for p in table.problems]},
        "values": values,
        "notes": summary["notes"],
        "errors": errors,
    }


def _wrap(items: Sequence[str], width: int = 96, indent: str = "    ") -> list[str]:
    lines, line = [], indent
    for item in items:
        if len(line) + len(item) + 2 > width and line.strip():
            lines.append(line.rstrip(", "))
            line = indent
        line += item + ", "
    if line.strip():
        lines.append(line.rstrip(", "))
    return lines


def format_report(report: dict[str, Any]) -> str:
    """The report as text for a terminal."""
    out = []
    for i in report["inputs"]:
        out.append(f"input   {i['source']}: {i['format']}")
        out.append(f"shape   {i['shape']['description']}")
        out.append(f"        ({i['shape']['why']})")
    a = report["atlas"]
    out.append(f"atlas   {a['name']}" + (f" (inferred: {a['reason']})" if a["inferred"] else " (given)"))
    if report["naming"]:
        out.append("naming  " + ", ".join(f"{k} ({v})" for k, v in report["naming"].items()))
    out.append(f"images  {report['n_images']}: " + ", ".join(report["images"][:8])
               + (", ..." if report["n_images"] > 8 else ""))
    regions = [n for n in report["names"] if n["status"] == REGION]
    out.append(f"\nregions {len(regions)} name(s) set {report['n_regions_with_value']} of "
               f"{report['n_regions_in_atlas']} {a['name']} regions:")
    for n in regions:
        out.append(f"    {n['name']:<40} -> {', '.join(n['regions'])}  [{n['naming']}]"
                   + (f"  ({n['atlas']})" if "atlas" in n else ""))
    ignored = [n for n in report["names"] if n["status"] == "ignored"]
    if ignored:
        out.append(f"\nnot regions ({len(ignored)}), set aside:")
        for n in ignored:
            out.append(f"    {n['name']:<40} {n['reason']}")
    unmatched = [n for n in report["names"] if n["status"] == UNMATCHED]
    if unmatched:
        out.append(f"\nunmatched ({len(unmatched)}): no {a['name']} region has these names")
        for n in unmatched:
            why = []
            if n.get("closest"):
                why.append("closest: " + ", ".join(n["closest"]))
            if n.get("region_of_atlas"):
                why.append("a region of atlas " + ", ".join(n["region_of_atlas"]))
            out.append(f"    {n['name']:<40} " + ("; ".join(why) if why else "no close name"))
    missing = report["regions_without_value"]
    if missing:
        out.append(f"\nregions without a value ({len(missing)}), drawn in the missing colour:")
        out.extend(_wrap(missing[:MAX_LISTED]))
        if len(missing) > MAX_LISTED:
            out.append(f"    ... and {len(missing) - MAX_LISTED} more (--json lists all)")
    cells = report["cells"]
    out.append(f"\ncells   {cells['n_empty']} empty (drawn in the NaN colour)")
    for p in cells["problems"]:
        if p["problem"] == "more":
            out.append("    ... and more")
            continue
        out.append(f"    {p['source']} {p['where']} column {p['column']!r}: {p['value']!r} is {p['problem']}")
    v = report["values"]
    if v["range"] is not None:
        out.append(f"values  {v['range'][0]:g} .. {v['range'][1]:g}")
    if v["scale"] is not None:
        s = v["scale"]
        out.append(f"scale   {s['name']}: {s['vmin']:g} .. {s['vmax']:g}"
                   + (f", centre {s['center']:g}" if s["center"] is not None else ""))
    for h in v["hints"]:
        out.append(f"        note: {h}")
    for note in report["notes"]:
        out.append(f"note    {note}")
    out.append("")
    out.append(("OK      " if report["ok"] else "ERROR   ") + report["summary"])
    if not report["ok"]:
        out.append(f"        render would stop: {report['errors'][0]}")
    return "\n".join(out)


def input_warnings(summary: dict[str, Any], max_names: int = 8) -> list[str]:
    """Warnings ``render``, ``figure`` and ``movie`` print about their input (as ``check`` reports it).

    Parameters
    ----------
    summary : dict
        :meth:`RegionTable.summary` (``manifest["input"]``).

    Returns
    -------
    list of str
        The notes (empty columns, decimal commas, images missing from an
        input) and the unmatched names, each with its closest region names.
    """
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.errors import BrainPainterError

    lines = list(summary.get("notes", []))
    unmatched = summary.get("unmatched_columns", [])
    if unmatched:
        try:
            resolver: NameResolver | None = NameResolver.for_atlas(get_atlas(summary["atlas"]))
        except BrainPainterError:  # an atlas from --atlas-config is not registered
            resolver = None
        shown = closest_each(unmatched, resolver.suggest if resolver is not None else lambda name: [],
                             max_names)
        lines.append(f"{len(unmatched)} name(s) match no {summary['atlas']} region and were not drawn: "
                     f"{shown}; see 'brainpainter check' (--strict makes this an error)")
    return lines
