"""What ``brainpainter check`` says about an input that is not a region table: a map or a connectome.

Each is read by the reader ``render`` uses (:func:`brainpainter.maps.inputs.read_maps`,
:func:`brainpainter.connectome.matrix.read_matrix`), so a file that checks is one that draws: the
report says what the file is (its format, mesh or size), how it would be drawn (resampling, colour
scale, node placement) and the command that draws it. A CIFTI dscalar used to get "contains NUL bytes:
it is binary, not a text table".
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.errors import BrainPainterError

#: CIFTI-2 file kinds by ending.
CIFTI_KINDS = {".dscalar.nii": "a CIFTI-2 dense scalar file", ".dtseries.nii": "a CIFTI-2 dense time series",
               ".dlabel.nii": "a CIFTI-2 dense label file", ".pscalar.nii": "a CIFTI-2 parcel scalar file",
               ".ptseries.nii": "a CIFTI-2 parcel time series", ".plabel.nii": "a CIFTI-2 parcel label file"}
_FORMATS = {".gii": "a GIfTI file", ".gii.gz": "a gzipped GIfTI file", ".mgh": "an MGH image",
            ".mgz": "an MGZ image", ".nii": "a NIfTI image", ".nii.gz": "a NIfTI image",
            ".npy": "a NumPy array", ".annot": "a FreeSurfer annotation", ".label": "a FreeSurfer label"}


def input_kind(path: Path) -> str | None:
    """``"map"`` or ``"connectome"`` where `path` is one by its ending or content
    (:func:`brainpainter.layers.readers.identify`; a ``.npy`` by its shape), else None (a table)."""
    from brainpainter.layers.readers import identify

    if not path.is_file():  # a FIFO, a device, a folder: never opened here (the table reader says why)
        return None
    if path.name.lower().endswith(".npy"):  # a map or a matrix: N x N of no mesh's size is a matrix
        return "connectome" if _square_npy(path) else "map"
    reader = identify(path, ("regions", "map", "connectome", *plugin_kinds()))
    return reader.kind if reader.kind != "regions" and reader.name != "nodes" else None


def plugin_kinds() -> list[str]:
    """The installed layer kinds read from a file of their own (``--layer KIND:FILE``: plugins')."""
    from brainpainter.atlas.registry import layer_kinds

    return [name for name in layer_kinds.names() if layer_kinds.get(name).open is not None]


def layer_report(path: Path, kind: str) -> dict[str, Any]:
    """What a plugin layer's file holds (its own summary) and how ``render --layer KIND:FILE`` draws it,
    read as render reads it (without ``--layer-opt`` values)."""
    from brainpainter.layers.kinds import kind_of

    of = kind_of(kind)
    layer = of.read(path, {})
    own = layer.layer()
    scale = own.scale
    return {"kind": kind, "source": str(path), "format": f"a {kind} file", "summary": layer.summary(),
            "label": own.label, "scale": f"{scale.name} {scale.vmin:.4g} .. {scale.vmax:.4g}",
            "draws": f"the {kind} layer ({of.description}), with its own colour bar labelled {own.label!r}",
            "command": f"brainpainter render --layer {kind}:{path} --out DIR", "errors": [], "notes": []}


def _square_npy(path: Path) -> bool:
    """Whether a ``.npy`` holds an N x N array of no mesh's vertex count (a matrix, not a map)."""
    from brainpainter.maps.resolution import FAMILY, FSLR

    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception:  # not readable here: the map reader says why
        return False
    return data.ndim == 2 and data.shape[0] == data.shape[1] > 1 and data.shape[0] not in {*FAMILY, *FSLR}


def square_matrix(path: Path) -> bool:
    """Whether a text file reads as a square matrix whose rows and columns carry the same names (a
    connectome, not a table whose images happen to be region names)."""
    from brainpainter.connectome.matrix import read_matrix

    try:
        m = read_matrix(path)
    except BrainPainterError:
        return False
    return m.names is not None and m.weights.shape[0] > 1


def map_report(path: Path) -> dict[str, Any]:
    """What a map file is and how ``render`` draws it (JSON-ready)."""
    from brainpainter.color.scale import ScaleOptions
    from brainpainter.maps.inputs import is_map_input
    from brainpainter.maps.layers import map_scale
    from brainpainter.maps.resolution import FAMILY, FSLR

    maps = _read_map(path)
    family = FSLR if maps.space == "fsLR" else FAMILY
    meshes = {hemi: f"{v.shape[1]:,} vertices ({family.get(v.shape[1], '?')})"
              for hemi, v in maps.values.items()}
    finite = np.concatenate([v[np.isfinite(v)] for v in maps.values.values()])
    report: dict[str, Any] = {
        "kind": "map", "source": str(path), "format": _format(path), "space": maps.space,
        "hemispheres": meshes, "n_images": len(maps.images), "images": list(maps.images[:5]),
        "notes": list(maps.notes), "errors": [],
        "n_values": int(finite.size),
        "value_range": [float(finite.min()), float(finite.max())] if finite.size else None,
        "zeros": float(np.mean(finite == 0)) if finite.size else 0.0,
        "regions": sorted(maps.regions or {}),
        "command": (f"brainpainter render {path} --out DIR" if is_map_input(path) else
                    f"brainpainter render --{next(iter(maps.values))} {path} --out DIR"),
    }
    if maps.categories is not None:
        report["categories"] = list(maps.categories)
        report["draws"] = f"a label map: {len(maps.categories)} labels, each in its own colour"
    else:
        scale = map_scale(ScaleOptions(), maps)
        report["scale"] = scale.describe()
        resampled = ("resampled onto fsaverage with HCP's fsLR weights" if maps.space == "fsLR" else
                     "on fsaverage (coarser meshes of its family brought to it)")
        report["draws"] = f"a map on the cortex, {resampled}, over sulcal-depth greys"
    if not finite.size:
        report["errors"].append(f"{path.name}: no finite value; nothing would be coloured.")
    return report


def _read_map(path: Path) -> Any:
    """The map as ``render FILE`` reads it (one hemisphere's file by its name, or a CIFTI's both)."""
    from brainpainter.maps.inputs import read_maps

    return read_maps(str(path))


def _format(path: Path) -> str:
    """The file's format in words: CIFTI kind by ending, else what its first bytes are."""
    from brainpainter.io.sniff import HEAD, described

    name = path.name.lower()
    for ending, kind in CIFTI_KINDS.items():
        if name.endswith(ending):
            return kind
    for ending, kind in _FORMATS.items():
        if name.endswith(ending):
            return kind
    with path.open("rb") as f:
        return described(f.read(HEAD)) or "a FreeSurfer curv file (old format)"


def connectome_report(path: Path) -> dict[str, Any]:
    """What a connectivity matrix is and how ``render --connectome`` draws it (JSON-ready)."""
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.connectome.matrix import read_matrix
    from brainpainter.connectome.order import node_order
    from brainpainter.connectome.sizes import atlases_taking, taking_text
    from brainpainter.table.names import infer_atlas
    from brainpainter.table.region_table import installed_atlases

    m = read_matrix(path)
    n = m.weights.shape[0]
    w = np.array(m.weights, dtype=np.float64)
    np.fill_diagonal(w, np.nan)
    edges = np.isfinite(w) & (w != 0)
    symmetric = bool(np.allclose(np.nan_to_num(w), np.nan_to_num(w.T), rtol=1e-6, atol=0))
    upper = edges & np.triu(np.ones_like(edges), 1).astype(bool)
    weights = w[upper if symmetric else edges]
    report: dict[str, Any] = {
        "kind": "connectome", "source": str(path), "format": f"a connectivity matrix, {n} x {n}",
        "n_nodes": n, "named": m.names is not None, "symmetric": symmetric,
        "n_edges": int(weights.size), "errors": [], "notes": [],
        "weight_range": [float(weights.min()), float(weights.max())] if weights.size else None,
    }
    atlas = None
    if m.names is not None:
        guess = infer_atlas(list(m.names), installed_atlases())
        if guess is not None:
            atlas = guess.atlas.name
            report["nodes"] = (f"names in the first row and column (e.g. {m.names[0]!r}); they fit atlas "
                               f"{atlas!r} ({guess.reason}): each node at its region's centroid")
        else:
            report["nodes"] = (f"names in the first row and column (e.g. {m.names[0]!r}) that name no region "
                               "of an installed atlas: give their places with --nodes (name,x,y,z)")
    else:
        installed, elsewhere = atlases_taking(n, node_order)
        atlas = installed[0] if len(installed) == 1 else None
        report["nodes"] = ("no names: the rows are placed in an atlas's node order; "
                           + taking_text(n, installed, elsewhere)
                           + ("" if atlas else "; give the one it was made in with --atlas, or --nodes"))
    if atlas is not None:
        report["atlas"] = get_atlas(atlas).name
    both = "" if symmetric else " (not symmetric: the upper triangle is drawn; --directed draws both)"
    report["draws"] = (f"{n} nodes and {report['n_edges']:,} edges{both}, each edge coloured by its weight "
                       "inside the glass cortex; --edge-threshold 99% keeps the strongest 1 %")
    report["command"] = (f"brainpainter render --connectome {path}" + (f" --atlas {atlas}" if atlas else "")
                         + " --out DIR")
    if not weights.size:
        report["errors"].append(f"{path.name}: no edge (every weight off the diagonal is 0 or empty).")
    return report


def format_input_report(report: dict[str, Any]) -> str:
    """The report of :func:`map_report` or :func:`connectome_report` as ``check`` prints it."""
    lines = [f"input   {report['source']}: {report['format']}"]
    if report["kind"] == "map":
        for hemi, mesh in report["hemispheres"].items():
            lines.append(f"mesh    {hemi}: {mesh}")
        lines.append(f"images  {report['n_images']}: {', '.join(report['images'])}"
                     + (" ..." if report["n_images"] > len(report["images"]) else ""))
        if report["value_range"] is not None:
            lo, hi = report["value_range"]
            lines.append(f"values  {lo:.4g} .. {hi:.4g} ({report['n_values']:,} finite, "
                         f"{report['zeros']:.1%} zeros)")
        if report["regions"]:
            lines.append(f"regions {len(report['regions'])} subcortical structure(s) with a mean value")
        if "scale" in report:
            lines.append(f"scale   {report['scale']}")
        lines.extend(f"note    {note}" for note in report["notes"])
    elif report["kind"] != "connectome":  # a plugin layer: its summary's plain entries, its scale
        lines += [f"{key:<7} {value}" for key, value in report["summary"].items()
                  if isinstance(value, str | int | float)]
        lines.append(f"scale   {report['scale']}")
    else:
        lines.append(f"nodes   {report['nodes']}")
        if report["weight_range"] is not None:
            lo, hi = report["weight_range"]
            lines.append(f"edges   {report['n_edges']:,} with a weight, {lo:.4g} .. {hi:.4g}"
                         + ("" if report["symmetric"] else ", not symmetric"))
    lines.append(f"draws   {report['draws']}")
    lines.append(f"command {report['command']}")
    lines.append("")
    lines.append(("ERROR   " + report["errors"][0]) if report["errors"] else
                 f"OK      {report['kind']}: render would draw it")
    return "\n".join(lines)
