"""Build time, size and start-up of the container image (docs/container.md), with podman.

    python benchmarks/bench_container.py                 # build with the layer cache, then measure
    python benchmarks/bench_container.py --no-cache      # a cold build (downloads every wheel)

Needs the base image ``localhost/debian-py:bookworm`` (tests/test_container.py makes it) or
``--base IMAGE``, root, podman and runc. Prints the build time, the image size and its layers, the
largest folders inside, and the median wall time of ``--version`` and of a one-view render (in the
container and on the host).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CA = "/etc/ssl/certs/ca-certificates.crt"
RENDER = ["render", "brainpainter_dk.csv", "--atlas", "dk", "--rows", "stage-4", "--views", "lateral-left",
          "--size", "800x600", "--out", "out/"]
INSIDE = ("du -sh /opt/brainpainter /opt/brainpainter/lib/python3*/site-packages/* /usr/lib/*-linux-gnu "
          "/usr/share 2>/dev/null | sort -h | tail -12")


def timed(cmd: list[str], **kw) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, **kw)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="localhost/debian-py:bookworm")
    parser.add_argument("--tag", default="brainpainter")
    parser.add_argument("--no-cache", action="store_true")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        conf = Path(tmp) / "containers.conf"
        conf.write_text("[containers]\ndefault_ulimits = []\n")
        os.environ["CONTAINERS_CONF"] = str(conf)
        podman = ["podman", "--runtime", "runc", "--cgroup-manager=cgroupfs"]
        build = [*podman, "build", "--format", "docker", "--network", "host", "-v", f"{CA}:{CA}:ro",
                 "--build-arg", f"BASE_IMAGE={args.base}", "-t", args.tag, "."]
        if args.no_cache:
            build.insert(len(podman) + 1, "--no-cache")
        print(f"build: {timed(build, cwd=REPO):.0f} s ({'no cache' if args.no_cache else 'layer cache'})")
        size = int(subprocess.run([*podman, "image", "inspect", "--format", "{{.Size}}", args.tag],
                                  check=True, capture_output=True, text=True).stdout)
        print(f"image size: {size / 1e9:.2f} GB ({size / 2**30:.2f} GiB)")
        subprocess.run([*podman, "image", "tree", args.tag], check=True)
        subprocess.run([*podman, "run", "--rm", "--network", "none", "--entrypoint", "sh", args.tag, "-c",
                        INSIDE], check=True)
        work = Path(tmp) / "work"
        work.mkdir()
        work.chmod(0o777)
        shutil.copy(REPO / "examples" / "brainpainter_dk.csv", work)
        run = [*podman, "run", "--rm", "--network", "none", "-v", f"{work}:/data", args.tag]
        rows = {
            "--version, container": [timed([*run, "--version"]) for _ in range(args.repeat)],
            "one 800x600 render, container": [timed([*run, *RENDER]) for _ in range(args.repeat)],
            "one 800x600 render, host": [timed([sys.executable, "-m", "brainpainter", *RENDER], cwd=work)
                                         for _ in range(args.repeat)],
        }
        for name, times in rows.items():
            print(f"{name}: median {statistics.median(times):.1f} s ({', '.join(f'{t:.1f}' for t in times)})")


if __name__ == "__main__":
    main()
