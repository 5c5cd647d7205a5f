"""10 images x 3 views of an fsLR 32k dscalar against the same of a DK region table (issue 34).

Same process, same views and size, each render timed end to end (reading, resampling onto
fsaverage, painting), interleaved (table, dscalar, dscalar, table, ... so neither always goes
first) so both see the same machine load, medians reported (min too); one untimed render of each
first, so the resampling weights are loaded and cached (as in any run after the first). Target:
the dscalar <= 1.5x the table.

    python benchmarks/bench_cifti.py [--repeat 5] [--size 800x600]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import nibabel as nib
import numpy as np
from nibabel.cifti2 import cifti2_axes as axes

N32 = 32492
VIEWS = "lateral-left,medial-left,lateral-right"


def dscalar(path: Path, n_maps: int = 10) -> Path:
    """A 32k dscalar of `n_maps` smooth random maps over both cortices (medial wall left out as HCP's 91k)."""
    rng = np.random.default_rng(0)
    cols = (axes.BrainModelAxis.from_surface(np.arange(0, N32, 1), N32, "CortexLeft")
            + axes.BrainModelAxis.from_surface(np.arange(0, N32, 1), N32, "CortexRight"))
    t = np.linspace(0, 6 * np.pi, 2 * N32)
    data = np.stack([np.sin(t * rng.uniform(0.5, 2)) for _ in range(n_maps)]).astype(np.float32)
    nib.Cifti2Image(data, header=(axes.ScalarAxis([f"map{i}" for i in range(n_maps)]), cols)).to_filename(
        path)
    return path


def dk_table(path: Path, n_rows: int = 10) -> Path:
    """A DK region table of `n_rows` rows (the example table's regions, random values)."""
    example = Path(__file__).resolve().parents[1] / "examples" / "brainpainter_dk.csv"
    header = example.read_text().splitlines()[0].split(",")
    rng = np.random.default_rng(0)
    rows = [",".join([f"row-{i}", *(f"{v:.3f}" for v in rng.uniform(0, 2, len(header) - 1))])
            for i in range(n_rows)]
    path.write_text("\n".join([",".join(header), *rows]) + "\n")
    return path


def main() -> None:
    import brainpainter
    from brainpainter.rendering.settings import parse_size

    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--size", default="800x600")
    args = ap.parse_args()
    w, h = parse_size(args.size)
    with tempfile.TemporaryDirectory() as tmp:
        inputs = {"table": dk_table(Path(tmp) / "dk.csv"), "dscalar": dscalar(Path(tmp) / "maps.dscalar.nii")}
        spent: dict[str, list[float]] = {"table": [], "dscalar": []}
        for r in range(-1, args.repeat):  # round -1: untimed (weights loaded, caches warm)
            for name in ("table", "dscalar") if r % 2 == 0 else ("dscalar", "table"):
                t = time.perf_counter()
                result = brainpainter.render(inputs[name], views=VIEWS, width=w, height=h, progress=False)
                if r >= 0:
                    spent[name].append(time.perf_counter() - t)
                assert len(result.images) == 30, len(result.images)
    out: dict[str, object] = {f"{k}_median_s": round(statistics.median(v), 2) for k, v in spent.items()}
    out.update({f"{k}_min_s": round(min(v), 2) for k, v in spent.items()})
    out["ratio_median"] = round(statistics.median(spent["dscalar"]) / statistics.median(spent["table"]), 2)
    out["ratio_min"] = round(min(spent["dscalar"]) / min(spent["table"]), 2)
    out["runs"] = {k: [round(x, 2) for x in v] for k, v in spent.items()}
    print(json.dumps(out))

if __name__ == "__main__":
    main()
