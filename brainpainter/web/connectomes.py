"""Connectome uploads of the web API: a matrix, and optionally its nodes, node values and categories.

A connectome upload (``POST /api/connectomes``) is one connectivity matrix (any format
``--connectome`` reads: CSV/TSV/text, ``.edge``, ``.npy``, ``.mat``, CIFTI ``.pconn.nii``) and, each
at most once, a nodes file (``name,x,y,z`` or BrainNet Viewer ``.node``: ``--nodes``), a file of node
values and one of node categories (``--node-values``, ``--node-categories``). They are read in a
process of their own (:func:`brainpainter.web.upload.read_connectome_upload`: killed after the
server's parse time limit, its data memory bounded) by the CLI's readers
(:mod:`brainpainter.connectome.matrix`,
:mod:`brainpainter.connectome.nodefiles`), which refuse a declared shape the file cannot hold (a
100000 x 100000 ``.npy`` header, a ``.mat`` bomb, a ``.pconn`` of huge dimensions) before allocating
it; a matrix of more than :data:`MAX_NODES` nodes is refused too.

What is kept is a *connectome bundle* (:data:`MAGIC`, one JSON line, then the files): what was read,
never the files as sent: the matrix as a float32 ``.npy`` (its node names, if it had any, in the
header), the nodes as a small table, the node values and categories as one line per entry. A render
names it by its upload id (option ``connectome``), or uploads it as its main upload (the connectome
alone); its files are then written once into ``DATA_DIR/incoming/connectome-<sha256>/`` and the run
gets them as the CLI's ``--connectome``, ``--nodes``, ``--node-values`` and ``--node-categories``
(:func:`materialise`).
"""

from __future__ import annotations

import csv
import json
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.web.bundle import bundle_header as read_header
from brainpainter.web.bundle import members, write_bundle, written_once

#: The first bytes of a stored connectome upload.
MAGIC = b"BRAINPAINTER-CONNECTOME/1\n"
#: What each file of an upload is (``role=``), in the order of the CLI's options.
ROLES = ("matrix", "nodes", "node_values", "node_categories")
#: The CLI option each role is given as.
OPTIONS = {"matrix": "--connectome", "nodes": "--nodes", "node_values": "--node-values",
           "node_categories": "--node-categories"}
#: The render options of a connectome's edges and nodes (given to a run only with a connectome upload, whose
#: files give --nodes, --node-values and --node-categories): :class:`ConnectomeOptions`'s.
CONNECTOME_FIELDS = ("directed", "edge_threshold", "top_edges", "edges_of", "nodes_space", "node_labels",
                     "node_labels_top", "node_labels_per_category")
#: Nodes a web connectome has at most (a 1000 x 1000 matrix is 4 MB as float32).
MAX_NODES = 1000


def connectome_fields() -> dict[str, Any]:
    """The fields of :class:`~brainpainter.web.options.RenderOptions` of a connectome's edges and nodes
    (:data:`CONNECTOME_FIELDS`), with the defaults, help and choices of
    :class:`~brainpainter.connectome.options.ConnectomeOptions` (the CLI's), bounded for a server."""
    from dataclasses import fields
    from typing import Literal

    from pydantic import Field

    from brainpainter.connectome.edges import MAX_EDGES_DRAWN
    from brainpainter.connectome.options import ConnectomeOptions

    of = {f.name: f for f in fields(ConnectomeOptions)}

    def made(name: str, kind: Any, **bounds: Any) -> tuple[Any, Any]:
        return kind, Field(of[name].default, description=of[name].metadata["help"], **bounds)

    return {"directed": made("directed", bool),
            "edge_threshold": made("edge_threshold", str | None, max_length=40),
            "top_edges": made("top_edges", int | None, ge=0, le=MAX_EDGES_DRAWN),
            "edges_of": made("edges_of", str | None, max_length=200),
            "nodes_space": made("nodes_space", Literal[of["nodes_space"].metadata["choices"]]),
            "node_labels": made("node_labels", bool),
            "node_labels_top": made("node_labels_top", int | None, ge=1, le=MAX_NODES),
            "node_labels_per_category": made("node_labels_per_category", bool)}


def is_connectome_bundle(data: bytes) -> bool:
    """Whether stored upload bytes are a connectome bundle."""
    return data.startswith(MAGIC)


def bundle_header(data: bytes) -> tuple[dict[str, Any], int]:
    """The JSON header of connectome bundle `data` and where its files start.

    Raises
    ------
    BrainPainterError
        The bundle is damaged.
    """
    return read_header(data, MAGIC, "role", ROLES,
                       "the stored connectome upload is damaged; upload the connectome again.")


def roles_of(names: list[str], roles: list[str]) -> list[str]:
    """The role of each file: given (``role=nodes``), else :data:`ROLES` in order (matrix, nodes, node
    values, node categories).

    Raises
    ------
    BrainPainterError
        An unknown role, a role given twice, no matrix, or another count of roles than of files.
    """
    if roles and len(roles) != len(names):
        raise BrainPainterError(f"{len(names)} files but {len(roles)} roles were given; give one role per "
                                f"file (role=matrix&role=nodes...), each one of {list(ROLES)}.")
    if not roles:
        roles = list(ROLES[:len(names)])
    for role in roles:
        if role not in ROLES:
            raise BrainPainterError(f"role must be one of {list(ROLES)}; {role[:40]!r} was given.")
    twice = sorted({r for r in roles if roles.count(r) > 1})
    if twice or "matrix" not in roles:
        wrong = f"role {twice[0]} was given twice" if twice else "no matrix was given"
        raise BrainPainterError(f"a connectome upload is one matrix and at most one file of each other role "
                                f"({list(ROLES)}); {wrong}.")
    return roles


# -- reading (in the process that upload.read_connectome_upload starts) -------------------------
def build_connectome_bundle(work: Path, files: dict[str, Path], max_nodes: int) -> dict[str, Any]:
    """Read the uploaded `files` (role -> path) with the CLI's readers and write ``work/bundle.bin``.

    Returns
    -------
    dict
        The report: ``kind`` (``"connectome"``), ``summary`` (one line), ``nodes`` (N), ``named``
        (whether the matrix names its nodes), ``edges`` (weights neither 0 nor NaN off the diagonal),
        ``files`` (role -> name as uploaded).

    Raises
    ------
    BrainPainterError
        What the readers refuse (one line), or more than `max_nodes` nodes.
    """
    from brainpainter.connectome.matrix import read_matrix
    from brainpainter.connectome.nodefiles import read_nodes

    m = read_matrix(files["matrix"])
    n = m.weights.shape[0]
    shown = files["matrix"].name
    if n > max_nodes:
        raise BrainPainterError(f"connectome matrix {shown!r} has {n} nodes; this server draws at most "
                                f"{max_nodes}. Render it with 'brainpainter render --connectome' on your own "
                                "computer, or give a matrix of fewer nodes.")
    kept = work / "kept"
    kept.mkdir()
    out: list[tuple[str | None, Path]] = [("matrix", kept / "matrix.npy")]
    np.save(out[0][1], _float32_weights(m.weights, shown))
    names: list[str] | None = None if m.names is None else [str(x) for x in m.names]
    if "nodes" in files:
        table = read_nodes(files["nodes"])
        if len(table.names) != n:
            raise BrainPainterError(
                f"nodes file {files['nodes'].name!r} has {len(table.names)} nodes but connectome matrix "
                f"{shown!r} has {n} rows; give one node per row of the matrix, in its order.")
        out.append(("nodes", _write_nodes(table, kept, files["nodes"].name.lower().endswith(".node"))))
        names = names or [str(x) for x in table.names]
    cells = {role: _node_cells(files[role], role, n, names) for role in ("node_values", "node_categories")
             if role in files}
    for role, entries in cells.items():  # as read and checked: one JSON list per role, in the nodes' order
        path = kept / f"{role}.json"
        path.write_text(json.dumps(entries))
        out.append((role, path))
    off = ~np.eye(n, dtype=bool)
    edges = int((np.isfinite(m.weights) & (m.weights != 0) & off).sum())
    report = {"kind": "connectome", "summary": f"{n} nodes, {edges} weights", "nodes": n,
              "named": m.names is not None, "edges": edges,
              "files": {role: path.name for role, path in files.items()}}
    write_bundle(work / "bundle.bin", MAGIC, {"report": report, "names": list(m.names or [])}, "role", out)
    return report


def _float32_weights(weights: NDArray[np.float64], shown: str) -> NDArray[np.float32]:
    """`weights` as kept (float32), refused where a weight is infinite or beyond float32's range.

    Raises
    ------
    BrainPainterError
        One line: the largest weight, the range allowed.
    """
    kept = weights.astype(np.float32)
    bad = np.isinf(kept) & ~np.isnan(weights)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise BrainPainterError(
            f"connectome matrix {shown!r} has weight {float(weights[i, j])!r} (row {i + 1}, column {j + 1}); "
            f"this server keeps weights within +-{float(np.finfo(np.float32).max):.3g} (float32). Rescale "
            "the matrix, or give NaN where there is no edge.")
    return kept


def _node_cells(path: Path, role: str, n: int, names: list[str] | None) -> list[Any]:
    """The node values (numbers, None where empty) or categories (texts) of an uploaded file, one per node
    in the matrix's order, read and checked as the CLI reads them (``--node-values``, ``--node-categories``).

    Raises
    ------
    BrainPainterError
        What the CLI refuses: another count of entries than `n`, a value that is not a finite number, a
        name that is no node.
    """
    from brainpainter.connectome.nodefiles import node_cells, node_texts, node_values

    what = role.replace("_", " ")
    entries = node_cells(str(path), n, what, names=names)
    if entries is None:  # pragma: no cover - a file is always given
        return []
    if role == "node_values":
        return [None if np.isnan(v) else float(v) for v in node_values(entries, path.name)]
    return list(node_texts(entries, numbers=True))


def _write_nodes(table: Any, folder: Path, brainnet: bool) -> Path:
    """A :class:`~brainpainter.connectome.nodefiles.NodeTable` written back: a BrainNet Viewer ``.node``
    (x y z colour size label) or a ``name,x,y,z,...`` CSV with its other columns."""
    if brainnet:
        path = folder / "nodes.node"
        cols = [table.columns.get(c, [""] * len(table.names)) for c in ("color", "size")]
        with path.open("w") as fh:
            for i, name in enumerate(table.names):
                x, y, z = (repr(float(v)) for v in table.positions[i])
                color, size = (str(c[i]).strip() or "1" for c in cols)
                fh.write(f"{x} {y} {z} {color} {size} {str(name).replace(' ', '_') or '-'}\n")
        return path
    path = folder / "nodes.csv"
    extra = [c for c in table.columns if c not in ("name", "x", "y", "z")]
    with path.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["name", "x", "y", "z", *extra])
        for i, name in enumerate(table.names):
            writer.writerow([name, *(repr(float(v)) for v in table.positions[i]),
                             *(table.columns[c][i] for c in extra)])
    return path


# -- drawing ------------------------------------------------------------------------------------
def report_of(data: bytes) -> dict[str, Any]:
    """The report a connectome bundle was stored with (nodes, edges, files)."""
    report: dict[str, Any] = dict(bundle_header(data)[0]["report"])
    return report


def materialise(data: bytes, root: Path) -> dict[str, Any]:
    """The files of connectome bundle `data` in ``root/incoming/connectome-<sha256>`` (written once, then
    reused), as the keywords of a run (``connectome``, ``nodes``: paths; ``node_values``, ``node_categories``:
    one entry per node, as the upload read them).

    A matrix that named its nodes is written as a CSV with its names (read back by name, as uploaded),
    else as the ``.npy`` kept (:func:`~brainpainter.web.bundle.written_once`).
    """
    header, start = bundle_header(data)

    def fill(work: Path) -> None:
        for f, content in members(data, header, start):
            target = work / ("matrix.npy" if f["role"] == "matrix" else Path(str(f["name"])).name)
            target.write_bytes(content)
        if header.get("names"):
            _named_csv(work / "matrix.npy", [str(n) for n in header["names"]], work / "matrix.csv")

    folder = written_once(data, root, "connectome", fill)
    out: dict[str, Any] = {
        "connectome": str(folder / ("matrix.csv" if (folder / "matrix.csv").is_file() else "matrix.npy"))}
    for f in header["files"]:
        path = folder / Path(str(f["name"])).name
        if f["role"] == "nodes":
            out["nodes"] = str(path)
        elif f["role"] != "matrix":  # values and categories: the entries as read (a JSON list), in order
            out[str(f["role"])] = json.loads(path.read_text())
    return out


def connectome_files(data: bytes, options: Any, connectome: bytes | None,
                     data_dir: Path | None) -> dict[str, Any] | None:
    """The files on disk of the connectome of a run (the run's keywords ``connectome``, ``nodes``, ...,
    and its layers' labels where `options` give none): the upload itself (the connectome alone) or option
    ``connectome``'s; None without one."""

    if is_connectome_bundle(data):
        if connectome is not None and connectome != data:
            raise BrainPainterError("the upload is a connectome already; give option connectome only with a "
                                    "region table, a map or tracts (or leave it out to draw it alone).")
        connectome = data
    elif options.connectome is not None and (connectome is None or not is_connectome_bundle(connectome)):
        raise BrainPainterError("option connectome names no connectome upload (it expired, or is a table); "
                                "upload the connectome again (POST /api/connectomes) and give its upload_id.")
    if connectome is None:
        return None
    root = data_dir if data_dir is not None else Path(tempfile.gettempdir()) / "brainpainter-web"
    out = materialise(connectome, root)
    files = report_of(connectome)["files"]  # the colour bars name the files as uploaded, as the CLI's do
    named = {"edges": files.get("matrix"), "nodes": files.get("node_categories") or files.get("node_values")}
    out.update({f"{kind}_label": name for kind, name in named.items()
                if name and getattr(options, f"{kind}_label", None) is None})
    return out


def _named_csv(npy: Path, names: list[str], target: Path) -> None:
    """The kept matrix `npy` written as a CSV with `names` in its first row and column (NaN kept)."""
    weights = np.load(npy, allow_pickle=False)
    with target.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["", *names])
        for name, row in zip(names, weights, strict=True):
            writer.writerow([name, *("NaN" if np.isnan(v) else repr(float(v)) for v in row)])
    npy.unlink()
