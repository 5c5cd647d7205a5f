"""The tract values of a run: bundle columns of the main table or ``--tract-values``.

:func:`run_tract_values` finds them (:func:`prepare_run <brainpainter.rendering.run.prepare_run>`
calls it before reading the region table, which then leaves the bundle columns out:
:func:`without_bundle_columns`); :func:`brainpainter.rendering.composition.tract_colors` colours
one image's bundles.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from brainpainter.atlas.model import Atlas
from brainpainter.errors import BrainPainterError, NoRegionColumnError
from brainpainter.rendering.options import Options, SceneOptions
from brainpainter.table.region_table import RegionTable, read_table
from brainpainter.tracts.model import TractSpec
from brainpainter.tracts.values import TractValues, is_long, read_tract_values


def run_tract_values(data: Any, options: Options) -> tuple[TractValues | None, bool]:
    """The tract values of a run: ``tract_values`` if given, else the main table's bundle columns, if any.

    Columns of the main table count as bundles when their canonical name is a bundle of ``tracts``
    (a file's name); without any, bundles are coloured by direction. A main table that is an
    along-tract profile (bundle and node columns, pyAFQ's ``tract_profiles.csv``) is tract values
    only: its errors are reported, and so is a profile none of whose bundles is drawn. Tract values
    that name none of the bundles drawn are an error (else the tracts would be drawn in direction
    colours under a colour bar of values they do not show).

    Returns
    -------
    values : TractValues or None
    bundles_only : bool
        Every value column of the main table is a bundle (it holds no region values), or there is
        no main table (``tract_values`` alone).
    """
    scene = options.scene
    if scene.tract_values is not None:
        return given_tract_values(scene), data is None
    spec = scene.tract_spec()
    if spec is None or data is None or isinstance(data, list):
        return None, False
    from brainpainter.io.readers import read_raw

    known = bundle_names(spec)
    # a stream (the web API's upload) is read again for the region table: back to where it was
    pos = data.tell() if hasattr(data, "seek") and hasattr(data, "tell") else None
    profile = False
    try:
        raw = read_raw(data)
        profile = is_long(raw)
        tv = read_tract_values(raw, scene.tract_value)
    except BrainPainterError:
        if profile:
            raise
        return None, False
    finally:
        if pos is not None:
            data.seek(pos)
    keep = [j for j, (name, _) in enumerate(tv.nodes) if name in known]
    if not keep and profile:
        raise _none_drawn("the table", tv, known)
    if not keep:
        return None, False
    return _only(tv, known), len(keep) == len(tv.nodes)


def _only(tv: TractValues, known: set[str]) -> TractValues:
    """`tv` with the values of the bundles in `known` only."""
    keep = [j for j, (name, _) in enumerate(tv.nodes) if name in known]
    names = {tv.nodes[j][0] for j in keep}
    cols = [j for j, key in enumerate(tv.keys) if key.split(":")[1] in names]
    return TractValues(tv.images, tuple(tv.keys[j] for j in cols), tv.values[:, cols],
                       tuple(tv.nodes[j] for j in keep))


def _none_drawn(what: str, tv: TractValues, known: set[str]) -> BrainPainterError:
    return BrainPainterError(
        f"the bundles of {what} {sorted(tv.bundles)[:6]} are none of the tracts drawn {sorted(known)[:6]}; "
        "name the tractogram files after the bundles (AF_L.trk, CST_right.tck, ...), the columns after "
        "the tractograms, or give the tractograms the values were measured on.")


def given_tract_values(scene: SceneOptions) -> TractValues | None:
    """``--tract-values`` read, checked to name at least one bundle of ``--tracts`` (None: not given).

    Values of bundles that are not drawn (no ``--tracts`` file) are left out, with a warning.
    """
    if scene.tract_values is None:
        return None
    tv = read_tract_values(scene.tract_values, scene.tract_value)
    spec = scene.tract_spec()
    if spec is None:
        return tv
    known = bundle_names(spec)
    name = Path(scene.tract_values).name if isinstance(scene.tract_values, str | Path) else "tract values"
    if not set(tv.bundles) & known:
        raise _none_drawn(f"--tract-values {name!r}", tv, known)
    left = [b for b in tv.bundles if b not in known]
    if left:
        warnings.warn(f"--tract-values {name!r}: {len(left)} bundle(s) with a value have no tractogram and "
                      f"were not drawn: {left[:6]}{' ...' if len(left) > 6 else ''} (the tractograms: "
                      f"{sorted(known)[:6]}); give their files to --tracts, named after the bundles.",
                      stacklevel=2)
        return _only(tv, known)
    return tv


def bundle_names(spec: TractSpec) -> set[str]:
    """The bundles of the tractograms to draw: their files' names, canonical (``AF_L.trk``: ``AF_left``)."""
    from brainpainter.tracts.names import canonical

    return {canonical(f.name[: -len(f.suffix)]) for f in spec.files}


def without_bundle_columns(data: Any, bundles: set[str]) -> Any:
    """The main table without its bundle columns (drawn as tract values), read once, for the region table.

    So that a table with region and bundle columns reports no bundle as an unmatched region name
    (nor fails under ``--strict``). The image column and the region columns stay as they are.
    """
    from dataclasses import replace

    from brainpainter.io.readers import read_raw
    from brainpainter.tracts.names import canonical

    raw = read_raw(data)
    keep = [j for j, name in enumerate(raw.header) if canonical(name) not in bundles]
    if len(keep) == len(raw.header):
        return raw
    return replace(raw, header=[raw.header[j] for j in keep],
                   rows=[[row[j] if j < len(row) else None for j in keep] for row in raw.rows])


def read_run_table(data: Any, atlas: Atlas | None, options: Options,
                   tract_values: TractValues | None) -> RegionTable:
    """The region table of a run's INPUT (its bundle columns left out where they are the tract values)."""
    if tract_values is not None and options.scene.tract_values is None:
        data = without_bundle_columns(data, {name for name, _ in tract_values.nodes})
    try:
        return read_table(data, atlas, **options.table.kwargs())
    except NoRegionColumnError as exc:
        spec = options.scene.tract_spec()
        if spec is None or tract_values is not None:
            raise
        raise NoRegionColumnError(f"{exc} Nor does any column name a bundle of --tracts "
                                  f"{sorted(bundle_names(spec))[:6]}.") from None
