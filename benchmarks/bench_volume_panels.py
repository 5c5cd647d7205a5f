"""A figure of slices, a glass-brain projection and 3-D views against nilearn's two plots (issue 45).

Writes the issue's volume (a sphere of radius 8 mm at MNI (40, -20, 50), value 5 over zeros, on
FSL's 2 mm MNI152 grid; ``--stat`` adds two more blobs, one negative) and times, interleaved in one
process:

* **brainpainter**: ``brainpainter.figure(volume=..., threshold=2.3, views=V1,V2,
  slices=["z=-20,10,50"], projections="z")``: 3 slices, 1 glass projection and 2 rendered 3-D
  views (volume projected onto the cortex, Blender renders, the figure laid out and written);
* **brainpainter, other volume**: the same figure of another volume (with or without ``--stat``'s two
  more blobs): the arms alternate, so each figure's values differ from the figure before's;
* **brainpainter, new renderer**: the same figure with no painter kept from the figure before (a
  figure of a new scene: the renderer started and the scene uploaded again; ``rendering/kept.py``);
* **brainpainter, views only**: the same figure without its panels (what the panels add);
* **nilearn**: ``plot_stat_map(display_mode="z", cut_coords=[-20, 10, 50])`` and
  ``plot_glass_brain(display_mode="z")`` of the same file, each saved as a PNG.

Both at the same dpi. The first call of each (imports, Blender's start, the template read) is
reported apart; the medians are of the ``--repeat`` calls after it, alternating the two, in wall
seconds and in the process's CPU seconds (every thread: less sensitive to a loaded machine).

    python benchmarks/bench_volume_panels.py [--repeat 7] [--dpi 300] [--size 1200x900] [--views ...]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

SLICES = [-20.0, 10.0, 50.0]


def write_volume(folder: Path, stat: bool, name: str = "sphere.nii.gz") -> Path:
    import nibabel as nib

    affine = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in (91, 109, 91)], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    data = np.where(np.linalg.norm(xyz - [40, -20, 50], axis=-1) <= 8, 5.0, 0.0)
    if stat:
        data += 5 * np.exp(-((xyz - [-44, -60, 10]) ** 2).sum(-1) / 50) - 5 * np.exp(
            -((xyz - [-2, 50, -8]) ** 2).sum(-1) / 72)
    image = nib.Nifti1Image(data.astype(np.float32), affine)
    image.header.set_sform(affine, 4)
    image.header.set_qform(affine, 4)
    path = folder / name
    nib.save(image, path)
    return path


def brainpainter_figure(path: Path, out: Path, args: argparse.Namespace, panels: bool = True,
                        new_renderer: bool = False) -> Callable[[], None]:
    import brainpainter

    width, height = (int(v) for v in args.size.split("x"))
    extra = {"slices": [f"z={','.join(f'{z:g}' for z in SLICES)}"], "projections": "z"} if panels else {}
    name = (f"brainpainter{'' if panels else '_views'}{'' if path.name == 'sphere.nii.gz' else '_other'}"
            f"{'_new' if new_renderer else ''}.png")

    def call() -> None:
        if new_renderer:  # no painter kept from the figure before (rendering/kept.py): a new scene's cost
            from brainpainter.rendering import kept

            kept.release()
        brainpainter.figure(None, volume=path, threshold=2.3, views=args.views, width=width, height=height,
                            out=out / name, dpi=args.dpi,
                            progress=False, **extra)
    return call


def nilearn_plots(path: Path, out: Path, args: argparse.Namespace) -> Callable[[], None]:
    def call() -> None:
        import matplotlib

        matplotlib.use("Agg")
        from nilearn import plotting

        display = plotting.plot_stat_map(str(path), threshold=2.3, display_mode="z", cut_coords=SLICES)
        display.savefig(str(out / "nilearn_stat_map.png"), dpi=args.dpi)
        display.close()
        glass = plotting.plot_glass_brain(str(path), threshold=2.3, display_mode="z", plot_abs=False,
                                          colorbar=True)
        glass.savefig(str(out / "nilearn_glass_brain.png"), dpi=args.dpi)
        glass.close()
    return call


def machine() -> str:
    names = [line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")]
    cpu = names[0] if names else platform.processor()
    load = os.getloadavg()[0]
    return f"{cpu}, {os.cpu_count()} cores, load average {load:.1f}, Python {platform.python_version()}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--dpi", type=float, default=300.0)
    parser.add_argument("--size", default="1200x900", help="pixels of each 3-D render (the default)")
    parser.add_argument("--views", default="lateral-right,dorsal", help="the two 3-D views")
    parser.add_argument("--stat", action="store_true", help="two more blobs, one negative")
    parser.add_argument("--keep", type=Path, default=None, help="write the PNGs to this folder")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.keep or Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        path = write_volume(Path(tmp), args.stat)
        other = write_volume(Path(tmp), not args.stat, "other.nii.gz")
        calls = {"brainpainter": brainpainter_figure(path, out, args),
                 "brainpainter_other_volume": brainpainter_figure(other, out, args),
                 "brainpainter_new_renderer": brainpainter_figure(path, out, args, new_renderer=True),
                 "brainpainter_views_only": brainpainter_figure(path, out, args, panels=False),
                 "nilearn": nilearn_plots(path, out, args)}
        first: dict[str, float] = {}
        times: dict[str, list[float]] = {name: [] for name in calls}
        cpu: dict[str, list[float]] = {name: [] for name in calls}
        for k in range(args.repeat + 1):
            for name, call in (list(calls.items()) if k % 2 == 0 else list(reversed(calls.items()))):
                start, cpu_start = time.perf_counter(), time.process_time()
                call()
                took = time.perf_counter() - start
                if k == 0:
                    first[name] = took
                else:
                    times[name].append(took)
                    cpu[name].append(time.process_time() - cpu_start)
        medians = {name: statistics.median(t) for name, t in times.items()}
        cpu_medians = {name: statistics.median(t) for name, t in cpu.items()}
        result = {"machine": machine(), "repeat": args.repeat, "dpi": args.dpi, "size": args.size,
                  "views": args.views, "first_s": {n: round(t, 3) for n, t in first.items()},
                  "median_s": {n: round(t, 3) for n, t in medians.items()},
                  "range_s": {n: [round(min(t), 3), round(max(t), 3)] for n, t in times.items()},
                  "ratio_brainpainter_over_nilearn": round(medians["brainpainter"] / medians["nilearn"], 2),
                  "cpu_median_s": {n: round(t, 3) for n, t in cpu_medians.items()},
                  "cpu_ratio": round(cpu_medians["brainpainter"] / cpu_medians["nilearn"], 2)}
        print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
