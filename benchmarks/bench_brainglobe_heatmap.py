"""Benchmark: the same mouse values drawn by brainpainter and by brainglobe-heatmap (3-D), offline.

Both draw the original BrainPainter's mouse meshes (the ``brainpainter-atlas-mouse`` distribution,
pip-installed into a throw-away folder): brainpainter as that atlas, brainglobe-heatmap from the same
region meshes written as a BrainGlobe format-3 atlas in a temporary BRAINGLOBE folder
(:mod:`brainpainter.testing.brainglobe`; micrometres, orientation asr; no network: the atlas is found
through ``BRAINGLOBE_CONFIG_DIR``). The values are row ``Image_0`` of the original's
``mouse_template.csv``. Views: brainpainter's ``dorsal``, brainglobe-heatmap's ``horizontal`` (its
camera ``top``), 1200x900 for brainpainter, brainrender's window size for brainglobe-heatmap.

Timed per image, interleaved (brainpainter, heatmap, brainpainter, ...), median of ``--reps``:

* brainpainter: one image from a loaded painter (render + PNG), as a table of many rows is drawn;
  and its scene load once (the first image's extra cost).
* brainglobe-heatmap: ``Heatmap(values, ...)`` + ``show()`` + ``screenshot`` (it builds its scene
  for every heatmap: that is its per-image cost).

Writes the side-by-side image to ``docs/atlases/mouse-vs-brainglobe-heatmap.png`` (``--out``).

    pip install brainglobe-heatmap          # its own dependencies: brainrender, vedo, VTK
    python benchmarks/bench_brainglobe_heatmap.py --reps 5

Needs ../shared/data/mouse/brainpainter2021 (BRAINPAINTER_MOUSE_DATA names another copy).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SOURCE = Path(os.environ.get("BRAINPAINTER_MOUSE_DATA",
                             REPO.parent / "shared" / "data" / "mouse" / "brainpainter2021"))
NAME = "brainpainter_mouse_100um"
VMIN, VMAX = 0.0, 3.0
ZOOM = 0.9  # brainrender frames the Allen atlas's extent; closer, the mouse fills its image as ours does


def mouse_values() -> dict[str, float]:
    import pandas as pd

    table = pd.read_csv(SOURCE / "mouse_template.csv")
    row = table.iloc[0]
    return {k: float(row[k]) for k in table.columns[1:] if np.isfinite(row[k])}


def write_brainglobe_copy(folder: Path, geometry: Any) -> None:
    """The drawn region meshes of the mouse scene as a BrainGlobe format-3 atlas (asr, micrometres)."""
    from brainpainter.testing.brainglobe import write_format3_atlas

    parts = [p for p in geometry.parts if p.kind in ("cortex", "subcortical")]
    every = np.vstack([p.vertices for p in parts]).astype(float) * 100.0  # the original's unit: ~0.1 mm
    lo = every.min(axis=0)

    def asr(v: np.ndarray) -> np.ndarray:  # RAS -> from anterior, from superior, from right (um)
        v = v.astype(float) * 100.0 - lo
        size = every.max(axis=0) - lo
        return np.column_stack([size[1] - v[:, 1], size[2] - v[:, 2], size[0] - v[:, 0]]) + 200.0

    structures = [{"id": 997, "acronym": "root", "name": "root", "structure_id_path": [997],
                   "rgb_triplet": [255, 255, 255]}]
    meshes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    all_v, all_f, n = [], [], 0
    for i, key in enumerate(geometry.keys, start=1):
        slot = geometry.slot_of[key]
        pieces = []
        for p in parts:
            tri = p.triangles[p.palette_index[p.triangles[:, 0]] == slot]
            if len(tri):
                used, inverse = np.unique(tri, return_inverse=True)
                pieces.append((asr(p.vertices[used]), inverse.reshape(-1, 3)[:, ::-1]))  # asr: left-handed
        if not pieces:
            continue
        offsets = np.cumsum([0] + [len(v) for v, _ in pieces])
        v = np.vstack([v for v, _ in pieces])
        f = np.vstack([f + o for (_, f), o in zip(pieces, offsets, strict=False)])
        meshes[i] = (v, f)
        all_v.append(v)
        all_f.append(f + n)
        n += len(v)
        structures.append({"id": i, "acronym": key, "name": key, "structure_id_path": [997, i],
                           "rgb_triplet": [200, 200, 200]})
    meshes[997] = (np.vstack(all_v), np.vstack(all_f))
    shape = tuple(int(s) for s in np.ceil((every.max(axis=0) - lo)[[1, 2, 0]] / 100.0) + 4)
    write_format3_atlas(folder, NAME, structures, meshes, np.zeros(shape, np.uint32))
    conf = folder / "config"
    conf.mkdir(exist_ok=True)  # BRAINGLOBE_CONFIG_DIR (set before brainrender is imported)
    (conf / "bg_config.conf").write_text(
        f"[default_dirs]\nbrainglobe_dir = {folder}\ninterm_download_dir = {folder}\n")


def heatmap_image(values: dict[str, float], out: Path) -> float:
    import brainglobe_heatmap as bgh

    t = time.perf_counter()
    # a slab holding the whole brain (its 3-D heatmap draws what lies between two planes)
    hm = bgh.Heatmap(values, position=0, thickness=20_000, orientation="horizontal", format="3D",
                     atlas_name=NAME, check_latest=False, interactive=False, cmap="Reds", vmin=VMIN,
                     vmax=VMAX, zoom=ZOOM)
    scene = hm.show()
    scene.screenshot(name=str(out))
    seconds = time.perf_counter() - t
    scene.close()
    return seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "atlases" / "mouse-vs-brainglobe-heatmap.png")
    args = ap.parse_args()
    if not (SOURCE / "mouse_template.csv").is_file():
        sys.exit(f"needs {SOURCE} (BRAINPAINTER_MOUSE_DATA)")
    from PIL import Image

    from brainpainter import Painter
    from brainpainter.io.output import png_bytes
    from brainpainter.rendering.views import get_view
    from brainpainter.testing import installed, pip_install

    work = Path(tempfile.mkdtemp(prefix="bp-bgh-"))
    # brainglobe-atlasapi reads BRAINGLOBE_CONFIG_DIR when imported: before brainrender is
    os.environ["BRAINGLOBE_CONFIG_DIR"] = str(work / "brainglobe" / "config")
    import brainrender

    brainrender.settings.OFFSCREEN = True
    brainrender.settings.INTERACTIVE = False
    brainrender.settings.SHOW_AXES = False
    site = pip_install(REPO / "plugins" / "atlases" / "brainpainter-atlas-mouse", work / "site", work / "src")
    values = mouse_values()
    with installed(site):
        from brainpainter.color.scale import make_scale

        t = time.perf_counter()
        painter = Painter("mouse")  # 1200x900, default quality and shading
        painter.load()
        load_s = time.perf_counter() - t
        write_brainglobe_copy(work / "brainglobe", painter.scene.geometry)
        scale = make_scale(cmap="Reds", vmin=VMIN, vmax=VMAX)  # the same colour map as the heatmap's
        view = get_view("dorsal")

        def ours() -> tuple[float, np.ndarray]:
            t = time.perf_counter()
            img = painter.paint(values, view, scale)
            png_bytes(img)
            return time.perf_counter() - t, img

        ours()
        heatmap_image(values, work / "warm.png")  # warm both (imports, first context)
        bp, bg = [], []
        for _ in range(args.reps):
            s, img = ours()
            bp.append(s)
            bg.append(heatmap_image(values, work / "heatmap.png"))
        painter.close()
    print(f"brainpainter: scene load {load_s:.2f} s; per image (dorsal, 1200x900, render + PNG) "
          f"median {statistics.median(bp):.3f} s of {args.reps}: {[round(x, 3) for x in bp]}")
    print(f"brainglobe-heatmap 3-D (Heatmap + show + screenshot, scene built per image): median "
          f"{statistics.median(bg):.3f} s of {args.reps}: {[round(x, 3) for x in bg]}")
    left = Image.fromarray(img).convert("RGB")
    right = Image.open(work / "heatmap.png").convert("RGB")
    right = right.resize((round(right.width * left.height / right.height), left.height))
    both = Image.new("RGB", (left.width + right.width, left.height), "white")
    both.paste(left, (0, 0))
    both.paste(right, (left.width, 0))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    both.resize((both.width // 3, both.height // 3)).save(args.out, optimize=True)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
