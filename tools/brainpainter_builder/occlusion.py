"""Ambient occlusion baked into a template: the builder's use of :mod:`brainpainter.atlas.occlusion`.

:func:`cortex_arrays` and :func:`subcortical_array` are what ``build.py``
writes (``ao_{surface}`` per cortex file, ``ao`` in ``subcortical.npz``);
:func:`add_to_template` bakes the same arrays into a template built before
occlusion existed, rewriting its files in place (deterministically, with
core's writer)::

    python -m brainpainter_builder.occlusion plugins/atlases/brainpainter_atlases/templates/fsaverage
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas import writer
from brainpainter.atlas.occlusion import BIAS_MM, CELL_MM, N_DIRECTIONS, ambient_occlusion, to_uint8


def manifest_entry() -> dict[str, Any]:
    """The template manifest's ``occlusion`` entry: how the stored arrays were baked."""
    return {"method": "depth maps over a Fibonacci sphere (brainpainter.atlas.occlusion)",
            "n_directions": N_DIRECTIONS, "cell_mm": CELL_MM, "bias_mm": BIAS_MM,
            "arrays": "cortex: ao_{surface}; subcortical: ao (structures together); uint8, 255 = open sky"}


def cortex_arrays(vertices: dict[str, NDArray[Any]], faces: NDArray[Any]) -> dict[str, NDArray[Any]]:
    """``ao_{surface}`` (uint8 per vertex) for every surface of one hemisphere mesh."""
    return {f"ao_{s}": to_uint8(ambient_occlusion(v, faces)) for s, v in vertices.items()}


def subcortical_array(vertices: NDArray[Any], faces: NDArray[Any]) -> NDArray[Any]:
    """``ao`` (uint8 per vertex) of all subcortical structures, baked together (they shade one another)."""
    return to_uint8(ambient_occlusion(vertices, faces))


def add_to_template(path: str | Path) -> dict[str, float]:
    """Bake occlusion into the template at `path` (in place); returns seconds per file."""
    path = Path(path)
    manifest = json.loads((path / "manifest.json").read_text(encoding="utf-8"))
    seconds: dict[str, float] = {}
    files = [e["file"] for ls in manifest["labels"].values() if "cortex" in ls
             for e in ls["cortex"].values() if "base" not in e]
    for file in files:
        t0 = time.perf_counter()
        with np.load(path / file, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files if not k.startswith("ao_")}
        surfaces = {s: arrays[s] for s in manifest["surfaces"] if s in arrays}
        arrays.update(cortex_arrays(surfaces, arrays["faces"]))
        writer.save_npz(path / file, arrays)
        seconds[file] = time.perf_counter() - t0
    if manifest.get("subcortical"):
        file = manifest["subcortical"]["file"]
        t0 = time.perf_counter()
        with np.load(path / file, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files if k != "ao"}
        arrays["ao"] = subcortical_array(arrays["vertices"], arrays["faces"])
        writer.save_npz(path / file, arrays)
        seconds[file] = time.perf_counter() - t0
    # where build.py puts it (after "bounds"), so that a rebuild gives the same bytes
    manifest.pop("occlusion", None)
    keys = list(manifest)
    at = keys.index("bounds") + 1 if "bounds" in keys else len(keys)
    manifest = {**{k: manifest[k] for k in keys[:at]}, "occlusion": manifest_entry(),
                **{k: manifest[k] for k in keys[at:]}}
    writer.write_json(path / "manifest.json", manifest)
    return seconds


if __name__ == "__main__":  # pragma: no cover - a maintenance script
    for folder in sys.argv[1:]:
        before = sum(p.stat().st_size for p in Path(folder).iterdir() if p.is_file())
        took = add_to_template(folder)
        after = sum(p.stat().st_size for p in Path(folder).iterdir() if p.is_file())
        for f, s in took.items():
            print(f"{f}: {s:.1f} s")
        print(f"{folder}: {sum(took.values()):.1f} s, {before / 1e6:.2f} MB -> {after / 1e6:.2f} MB")
