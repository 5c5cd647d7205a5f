"""Peak memory of writing a long GIF movie (issue 11: GIF frames are streamed, not kept).

Writes N composed-size frames (smoothly changing colours, like a movie) through
brainpainter.media.movie._GifWriter and prints the peak resident memory of the process
(VmHWM) against the memory the frames themselves would take if kept in a list.

    python benchmarks/gif_memory.py [N] [WIDTH] [HEIGHT] [--old PATH/TO/OLD/movie.py]

``--old`` runs the writer of another checkout's movie.py instead (e.g. main before
issue 11, which kept every frame), for a peer measured on the same machine.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def peak_mb() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main() -> None:
    import importlib.util

    from brainpainter.io.verify import gif_info

    args = sys.argv[1:]
    old = None
    if "--old" in args:
        i = args.index("--old")
        old = args[i + 1]
        del args[i:i + 2]
    if old:
        spec = importlib.util.spec_from_file_location("old_movie", old)
        module = importlib.util.module_from_spec(spec)
        sys.modules["old_movie"] = module
        spec.loader.exec_module(module)
        writer_class = module._GifWriter
    else:
        from brainpainter.media.movie import _GifWriter as writer_class
    n = int(args[0]) if len(args) > 0 else 325
    w = int(args[1]) if len(args) > 1 else 1200
    h = int(args[2]) if len(args) > 2 else 500
    y, x = np.mgrid[0:h, 0:w]

    def frame(i: int) -> np.ndarray:
        t = i / max(1, n - 1)
        img = np.empty((h, w, 3), np.uint8)
        img[..., 0] = (255 * (0.5 + 0.5 * np.sin(x / 90 + 6 * t))).astype(np.uint8)
        img[..., 1] = (255 * (0.5 + 0.5 * np.cos(y / 70 + 3 * t))).astype(np.uint8)
        img[..., 2] = 128
        img[: h // 5] = 255  # a still background band
        return img

    before = peak_mb()
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "movie.gif"
        t0 = time.perf_counter()
        if old:
            writer = writer_class(path, (w, h), 24.0, (255, 255, 255))
        else:
            samples = [frame(i) for i in np.linspace(0, n - 1, 12).round().astype(int)]
            writer = writer_class(path, (w, h), 24.0, (255, 255, 255), samples)
            del samples
        for i in range(n):
            writer.write(frame(i))
        writer.close()
        seconds = time.perf_counter() - t0
        size = path.stat().st_size
        assert gif_info(path) == ((w, h), n)
    kept = n * w * h * 3 / 2**20
    label = "old (main) " if old else ""
    print(f"{label}{n} frames of {w}x{h}: {seconds:.1f} s, GIF {size / 2**20:.1f} MB; peak RSS "
          f"{peak_mb():.0f} MB (before writing {before:.0f} MB); keeping the frames would take {kept:.0f} MB")


if __name__ == "__main__":
    main()
