"""A BrainGlobe atlas written in format 3, as ``brainglobe-atlasapi`` 3 reads it, for tests and benchmarks.

``FOLDER/brainglobe-atlasapi/``: ``atlases/NAME/1_0/manifest.json``, the terminology
(``terminologies/NAME/1_0/terminology.csv``), the template and the annotation as OME-Zarr
(``templates/NAME/1_0/template.ome.zarr``, ``annotation-sets/NAME/1_0/annotations_compressed.ome.zarr``)
and one Draco mesh per structure (``annotation-sets/NAME/1_0/annotations.precomputed/mesh/ID``).
Read it back with ``BrainGlobeAtlas(NAME, brainglobe_dir=FOLDER, check_latest=False)`` or
``brainpainter atlas add X --brainglobe NAME --brainglobe-dir FOLDER``: no network.

Needs ``zarr`` and ``DracoPy`` (both come with brainglobe-atlasapi).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray


def write_format3_atlas(folder: str | Path, name: str, structures: Sequence[Mapping[str, Any]],
                        meshes: Mapping[int, tuple[NDArray[Any], NDArray[Any]]], annotation: NDArray[Any],
                        resolution: float = 100.0, species: str = "Mouse (Mus musculus)") -> Path:
    """Write an atlas in BrainGlobe's format 3 (orientation ``asr``); return `folder`.

    Parameters
    ----------
    folder : path
        Becomes the ``--brainglobe-dir`` (created).
    name : str
        The atlas name (``tiny_mouse_100um``).
    structures : sequence of dict
        BrainGlobe structure records: ``id``, ``acronym``, ``name``, ``structure_id_path`` (ids from the
        root), ``rgb_triplet``.
    meshes : mapping of int to (vertices, faces)
        Per structure id: vertices, shape (n, 3), in micrometres on the ``asr`` axes (from anterior, from
        superior, from right); triangles, shape (m, 3).
    annotation : ndarray of int, shape (a, s, r)
        Structure id per voxel (``asr``); the template is its mask.
    resolution : float
        Voxel size in micrometres.
    """
    import DracoPy
    import zarr

    root = Path(folder) / "brainglobe-atlasapi"
    where = {"terminology": f"terminologies/{name}/1_0", "annotation": f"annotation-sets/{name}/1_0",
             "template": f"templates/{name}/1_0"}
    for rel in where.values():
        (root / rel).mkdir(parents=True, exist_ok=True)
    rows = ["identifier,parent_identifier,abbreviation,name,root_identifier_path,color_hex_triplet"]
    for s in structures:
        path = [int(i) for i in s["structure_id_path"]]
        parent = str(path[-2]) if len(path) > 1 else ""
        colour = "#" + "".join(f"{int(c):02x}" for c in s["rgb_triplet"])
        ids = ",".join(map(str, path))
        rows.append(f'{s["id"]},{parent},{s["acronym"]},"{s["name"]}","[{ids}]",{colour}')
    (root / where["terminology"] / "terminology.csv").write_text("\n".join(rows) + "\n")
    ann = np.asarray(annotation, np.uint32)
    for arr, rel, file in ((ann, where["annotation"], "annotations_compressed.ome.zarr"),
                           ((ann > 0).astype(np.uint16) * 100, where["template"], "template.ome.zarr")):
        # OME-NGFF 0.4 written with zarr itself (ngff-zarr's writer needs numpy >= 2.1 for DLPack)
        group = zarr.open_group(str(root / rel / file), mode="w", zarr_format=2)
        group.attrs["multiscales"] = [{
            "version": "0.4", "name": "image",
            "axes": [{"name": d, "type": "space", "unit": "millimeter"} for d in "zyx"],
            "datasets": [{"path": "0", "coordinateTransformations": [
                {"type": "scale", "scale": [resolution / 1000] * 3}]}]}]
        group.create_array("0", shape=arr.shape, dtype=arr.dtype, chunks=arr.shape)[:] = arr
    mesh_dir = root / where["annotation"] / "annotations.precomputed" / "mesh"
    mesh_dir.mkdir(parents=True, exist_ok=True)
    for sid, (v, f) in meshes.items():  # atlasapi reads nanometres xyz back into micrometres zyx (asr)
        points = (np.asarray(v, np.float64)[:, ::-1] * 1000).astype(np.float32)
        (mesh_dir / str(sid)).write_bytes(DracoPy.encode(points, np.asarray(f)[:, ::-1].astype(np.uint32)))
    manifest = {
        "name": name, "version": "1.0", "species": species, "citation": "unpublished",
        "atlas_link": "https://example.org", "orientation": "asr", "symmetric": True,
        "resolution": [resolution] * 3, "shape": list(ann.shape),
        "terminology": {"location": "/" + where["terminology"]},
        "annotation_set": {"location": "/" + where["annotation"],
                           "template": {"location": "/" + where["template"]}},
    }
    atlas = root / "atlases" / name / "1_0"
    atlas.mkdir(parents=True, exist_ok=True)
    (atlas / "manifest.json").write_text(json.dumps(manifest))
    return Path(folder)
