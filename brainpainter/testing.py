"""Helpers for testing brainpainter plugins (usable from any pytest suite).

``fake_distribution`` writes a minimal installed distribution (a package plus
its ``.dist-info`` with ``entry_points.txt``) into a folder, exactly what pip
would leave in site-packages; put that folder on ``sys.path`` and call
:func:`brainpainter.registry.reset_all` to make the registries see it.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path


def fake_distribution(
    root: Path,
    name: str,
    entry_points: Mapping[str, Mapping[str, str]],
    files: Mapping[str, str],
    version: str = "0.1.0",
) -> Path:
    """Write an installed distribution into `root`.

    Parameters
    ----------
    root : Path
        Folder that will go on ``sys.path`` (like site-packages).
    name : str
        Distribution name.
    entry_points : mapping
        ``{group: {entry name: "module:attr"}}``.
    files : mapping
        ``{relative path: text}`` of the package's files.
    """
    root.mkdir(parents=True, exist_ok=True)
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    dist = root / f"{name.replace('-', '_')}-{version}.dist-info"
    dist.mkdir(exist_ok=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    lines = []
    for group, entries in entry_points.items():
        lines.append(f"[{group}]")
        lines.extend(f"{k} = {v}" for k, v in entries.items())
        lines.append("")
    (dist / "entry_points.txt").write_text("\n".join(lines))
    return root


@contextmanager
def installed(root: Path) -> Iterator[None]:
    """Put `root` on ``sys.path`` and refresh the registries for the duration."""
    from brainpainter import registry

    sys.path.insert(0, str(root))
    registry.reset_all()
    try:
        yield
    finally:
        sys.path.remove(str(root))
        for mod in [m for m, v in sys.modules.items() if str(root) in str(getattr(v, "__file__", "") or "")]:
            del sys.modules[mod]
        registry.reset_all()


def write_tiny_template(path: Path, labels: Mapping[str, tuple[str, ...]] | None = None) -> Path:
    """Write a small synthetic template (two icospheres, two boxes, glass spheres).

    Each hemisphere is an icosphere of radius 50 mm centred at x = -/+ 60 mm,
    split into the given label names by angle around the y axis (the first
    name on the anterior pole side). Subcortical: ``Left-Hippocampus`` and
    ``Right-Hippocampus`` boxes. Meant for fast tests of renderers and the
    core; coordinates are RAS millimetres like a real template.

    Parameters
    ----------
    path : Path
        Folder to create.
    labels : mapping of label-set name to label names, optional
        Default: ``{"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}``.
    """
    import json

    import numpy as np
    import trimesh

    from brainpainter.template import FORMAT, FORMAT_VERSION

    labels = labels or {"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}
    path.mkdir(parents=True, exist_ok=True)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=50.0)
    verts0 = np.asarray(sphere.vertices, dtype=np.float32)
    faces = np.asarray(sphere.faces, dtype=np.int32)
    centroids = verts0[faces].mean(axis=1)
    angle = np.arctan2(centroids[:, 2], centroids[:, 1])  # around the x axis, 0 = anterior
    manifest: dict = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "name": "tiny",
        "source": {"subject": "synthetic", "freesurfer_version": "none"},
        "space": "RAS millimetres", "surfaces": ["pial", "white", "inflated"],
        "labels": {}, "bounds": {}, "license": "CC0", "attribution": "synthetic",
    }
    offsets = {"lh": -60.0, "rh": 60.0}
    for name, names in labels.items():
        bins = np.linspace(-np.pi, np.pi, len(names) + 1)
        face_label = (np.clip(np.digitize(-angle, bins) - 1, 0, len(names) - 1)).astype(np.int16)
        manifest["labels"][name] = {"source": "synthetic", "cortex": {}}
        for hemi, dx in offsets.items():
            verts = verts0 + np.array([dx, 0, 0], np.float32)
            file = f"cortex-{hemi}-{name}.npz"
            np.savez_compressed(path / file, faces=faces, face_label=face_label, pial=verts,
                                white=verts * 0.95, inflated=verts + np.float32(np.sign(dx) * 10),
                                source_vertex=np.arange(len(verts), dtype=np.int32))
            manifest["labels"][name]["cortex"][hemi] = {
                "file": file, "names": list(names), "n_vertices": len(verts),
                "n_faces": len(faces), "open_edges": 0}
    boxes = [trimesh.creation.box(extents=(10, 20, 10)).apply_translation((dx / 3, 0, 0))
             for dx in offsets.values()]
    sub_v = np.concatenate([b.vertices for b in boxes]).astype(np.float32)
    sub_f = np.concatenate([boxes[0].faces, boxes[1].faces + len(boxes[0].vertices)]).astype(np.int32)
    sub_l = np.repeat(np.arange(2, dtype=np.int16), [len(b.faces) for b in boxes])
    np.savez_compressed(path / "subcortical.npz", vertices=sub_v, faces=sub_f, face_label=sub_l)
    manifest["subcortical"] = {"file": "subcortical.npz", "structures": [
        {"name": "Left-Hippocampus", "index": 17}, {"name": "Right-Hippocampus", "index": 53}]}
    manifest["glass"] = {}
    for hemi, dx in offsets.items():
        glass = trimesh.creation.icosphere(subdivisions=2, radius=52.0).apply_translation((dx, 0, 0))
        np.savez_compressed(path / f"glass-{hemi}.npz", vertices=glass.vertices.astype(np.float32),
                            faces=glass.faces.astype(np.int32))
        manifest["glass"][hemi] = {"file": f"glass-{hemi}.npz", "n_faces": len(glass.faces)}
    lo = (verts0 + np.array([-60, 0, 0])).min(axis=0).tolist()
    hi = (verts0 + np.array([60, 0, 0])).max(axis=0).tolist()
    manifest["bounds"] = {"pial": [lo, hi]}
    (path / "manifest.json").write_text(json.dumps(manifest, indent=1))
    return path
