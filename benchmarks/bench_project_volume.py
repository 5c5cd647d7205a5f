"""Time and memory of projecting a 2 mm MNI152 volume onto fsaverage (issue 21: under 1 s).

Writes a 2 mm MNI152 volume (91 x 109 x 91, FSL's grid; smooth random values, gzip NIfTI
like a statistical map), then times ``brainpainter.project_volume`` on it: the first call
(reads the shipped registration-fusion positions) and the median of ``--repeat`` warm calls,
each from the file on disk. Also times ``subcortical_means`` and, with ``--nilearn``,
``nilearn.surface.vol_to_surf`` on fsaverage5's pial surface (both hemispheres), in the same run;
``--projection`` chooses how each vertex is sampled (default ``ribbon``).
Prints the peak resident memory of the process (VmHWM) and what the projection added to it.

    python benchmarks/bench_project_volume.py [--repeat 7] [--volumes 1] [--nilearn] [--projection point]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np


def peak_mb() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def write_volume(folder: Path, n_volumes: int) -> Path:
    import nibabel as nib
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(0)
    affine = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
    shape = (91, 109, 91) if n_volumes == 1 else (91, 109, 91, n_volumes)
    data = gaussian_filter(rng.standard_normal(shape).astype(np.float32), sigma=(2, 2, 2, 0)[: len(shape)])
    path = folder / "zstat_2mm.nii.gz"
    nib.save(nib.Nifti1Image(data, affine), path)
    return path


def timed(call, repeat: int) -> tuple[float, float]:
    """(first call, median of `repeat` further calls) in seconds."""
    start = time.perf_counter()
    call()
    first = time.perf_counter() - start
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return first, statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--volumes", type=int, default=1, help="volumes in the file (4-D when > 1)")
    parser.add_argument("--nilearn", action="store_true", help="time nilearn's vol_to_surf too")
    parser.add_argument("--projection", choices=("ribbon", "line", "point"), default="ribbon",
                        help="how each vertex is sampled (project_volume's projection)")
    args = parser.parse_args()
    from brainpainter.maps.volume import project_volume, subcortical_means

    with tempfile.TemporaryDirectory() as tmp:
        path = write_volume(Path(tmp), args.volumes)
        before = peak_mb()
        first, median = timed(lambda: project_volume(path, projection=args.projection), args.repeat)
        after = peak_mb()
        print(f"project_volume ({args.projection}), {args.volumes} volume(s) of 91x109x91 (2 mm): first call "
              f"{first:.3f} s, median of {args.repeat} {median:.3f} s")
        print(f"peak memory {after:.0f} MB (before projecting {before:.0f} MB: +{after - before:.0f} MB)")
        first, median = timed(lambda: subcortical_means(path), args.repeat)
        print(f"subcortical_means: first call {first:.3f} s, median {median:.3f} s")
        if args.nilearn:
            from nilearn import datasets, surface

            mesh = datasets.load_fsaverage("fsaverage5")["pial"]

            def both() -> None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    for part in ("left", "right"):
                        surface.vol_to_surf(str(path), mesh.parts[part])

            first, median = timed(both, args.repeat)
            print(f"nilearn vol_to_surf (fsaverage5 pial, 2 x 10242 vertices): first {first:.3f} s, "
                  f"median {median:.3f} s")


if __name__ == "__main__":
    main()
