"""The container image (``Containerfile``), built and run with podman.

The base image is made locally (container registries are not reachable from CI):
``debootstrap --variant=minbase`` of Debian bookworm with Python 3.11, imported as
``localhost/debian-py:bookworm`` and kept in podman's storage between runs. The image is then built
exactly as a user builds it (pip installs the locked dependencies from the package index, so the build
uses the host network and its CA bundle); everything else runs the image.

Checked: the version inside and the labels equal the package version; the process is not root and an
arbitrary ``--user`` owns what it writes; a render in a container without network is the host's render
(within 1 RGB unit); ``serve`` answers its health check, runs a job over HTTP on 127.0.0.1 and still
lists it after the container is restarted.

Needs root, podman, runc and debootstrap (``.ci/run`` installs them); elsewhere the tests are skipped
with the reason. Runs in the Python 3.11 pass of CI only (the image's Python). Timings (build, image
size) are printed with ``-s`` and recorded in docs/container.md.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from web_support import CLIENT, free_port, png_pixels, wait_for

httpx = pytest.importorskip("httpx")

pytestmark = pytest.mark.container

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
BASE = "localhost/debian-py:bookworm"
IMAGE = "brainpainter"  # podman names it localhost/brainpainter:latest
CA_BUNDLE = "/etc/ssl/certs/ca-certificates.crt"
# the render compared with the host's: two views of one row, small enough to be quick
RENDER_ARGS = ["render", "brainpainter_dk.csv", "--atlas", "dk", "--rows", "stage-4",
               "--views", "lateral-left,subcortical", "--size", "400x300"]


def _missing_requirements() -> str | None:
    if sys.version_info[:2] != (3, 11):
        return ("the image is built on Debian bookworm's Python 3.11; the container tests run in the "
                "Python 3.11 pass of CI")
    missing = [tool for tool in ("podman", "runc", "debootstrap") if shutil.which(tool) is None]
    if missing:
        return f"{', '.join(missing)} not installed (apt-get install podman runc debootstrap; .ci/run does)"
    if os.geteuid() != 0:
        return "debootstrap and rootful podman need root (CI runs as root)"
    return None


@pytest.fixture(scope="module")
def podman(tmp_path_factory: pytest.TempPathFactory) -> Iterator[list[str]]:
    """The podman command line that works on these machines (runc, cgroupfs, no default ulimits)."""
    reason = _missing_requirements()
    if reason:
        pytest.skip(reason)
    conf = tmp_path_factory.mktemp("podman") / "containers.conf"
    conf.write_text("[containers]\ndefault_ulimits = []\n")
    mp = pytest.MonkeyPatch()
    mp.setenv("CONTAINERS_CONF", str(conf))
    yield ["podman", "--runtime", "runc", "--cgroup-manager=cgroupfs"]
    mp.undo()


def run(cmd: list[str], timeout: float = 600, check: bool = True, **kw) -> subprocess.CompletedProcess:
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kw)
    if check and proc.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stdout[-3000:]}\n"
                             f"{proc.stderr[-3000:]}")
    return proc


def _make_base(podman: list[str]) -> None:
    """debootstrap bookworm (minbase + python3-venv + CA certificates) and import it as BASE (~2-3 min)."""
    with tempfile.TemporaryDirectory(prefix="bp-debootstrap-") as tmp:
        rootfs = Path(tmp) / "rootfs"
        run(["debootstrap", "--variant=minbase", "--include=python3,python3-venv,ca-certificates",
             "bookworm", str(rootfs)], timeout=1200)
        # not part of a base image: the downloaded packages, package lists, manuals, translations and
        # documentation (the packages' copyright files stay)
        for folder in ("var/cache/apt/archives", "var/lib/apt/lists", "usr/share/man", "usr/share/locale",
                       "usr/share/info", "usr/share/doc"):
            for entry in (rootfs / folder).rglob("*"):
                if entry.is_file() and entry.name != "copyright":
                    entry.unlink()
        with subprocess.Popen(["tar", "-C", str(rootfs), "-c", "."], stdout=subprocess.PIPE) as tar:
            run([*podman, "import", "-", BASE], stdin=tar.stdout, timeout=600)
        assert tar.returncode == 0


@pytest.fixture(scope="module")
def image(podman: list[str]) -> str:
    """Build the image (layers cached by podman between runs); print the build time and image size."""
    if run([*podman, "image", "exists", BASE], check=False).returncode != 0:
        _make_base(podman)
    start = time.monotonic()
    run([*podman, "build", "--format", "docker", "--network", "host",
         "-v", f"{CA_BUNDLE}:{CA_BUNDLE}:ro", "--build-arg", f"BASE_IMAGE={BASE}", "-t", IMAGE, "."],
        cwd=REPO, timeout=2400)
    run([*podman, "image", "prune", "-f"])  # earlier builds' untagged layers: disk use stays bounded
    size = int(run([*podman, "image", "inspect", "--format", "{{.Size}}", IMAGE]).stdout)
    print(f"\ncontainer image built in {time.monotonic() - start:.0f} s; size {size / 1e9:.2f} GB")
    return IMAGE


def test_version_labels_and_licences(podman, image):
    version = metadata.version("brainpainter")
    assert run([*podman, "run", "--rm", "--network", "none", image, "--version"]).stdout.strip() \
        == f"brainpainter, version {version}"
    labels = json.loads(run([*podman, "image", "inspect", "--format", "{{json .Labels}}", image]).stdout)
    assert labels["org.opencontainers.image.version"] == version
    assert labels["org.opencontainers.image.source"].startswith("https://")
    assert "MIT" in labels["org.opencontainers.image.licenses"]
    listed = run([*podman, "run", "--rm", "--network", "none", "--entrypoint", "ls", image,
                  "/usr/share/licenses/brainpainter"]).stdout.split()
    assert {"LICENSE", "fsaverage-template.LICENSE.FreeSurfer.txt", "three.js.LICENSE.txt"} <= set(listed)


def test_runs_as_a_user_not_root(podman, image):
    ids = run([*podman, "run", "--rm", "--network", "none", "--entrypoint", "id", image]).stdout
    assert ids.startswith("uid=1000(brainpainter)"), ids


def _host_render(folder: Path) -> None:
    shutil.copy(EXAMPLE, folder / EXAMPLE.name)
    run([sys.executable, "-m", "brainpainter", *RENDER_ARGS, "--out", "out/"], cwd=folder, timeout=900)


def test_render_without_network_matches_the_host(podman, image, tmp_path):
    lock = (REPO / "container" / "requirements-py311.txt").read_text()
    pinned = re.search(r"^bpy==(\S+)$", lock, re.MULTILINE)
    assert pinned and pinned[1] == metadata.version("bpy"), (
        f"the image's lock pins bpy {pinned and pinned[1]}, this environment has {metadata.version('bpy')}: "
        "run python container/lock.py > container/requirements-py311.txt here (where the tests pass)")
    host, box = tmp_path / "host", tmp_path / "container"
    host.mkdir()
    box.mkdir()
    _host_render(host)
    shutil.copy(EXAMPLE, box / EXAMPLE.name)
    box.chmod(0o777)  # the caller's folder: writable by the --user below
    run([*podman, "run", "--rm", "--network", "none", "--user", "12345:12345", "-v", f"{box}:/data",
         image, *RENDER_ARGS, "--out", "out/"], timeout=900)
    names = sorted(p.name for p in (host / "out").glob("*.png"))
    assert names == ["stage-4_lateral-left.png", "stage-4_subcortical.png"]
    for name in names:
        made = box / "out" / name
        assert made.stat().st_uid == 12345  # the calling user owns the output, not root
        ours = np.asarray(Image.open(made).convert("RGBA")).astype(int)
        theirs = np.asarray(Image.open(host / "out" / name).convert("RGBA")).astype(int)
        assert ours.shape == theirs.shape == (300, 400, 4)
        assert np.abs(ours - theirs).max() <= 1, name
        drawn = (np.abs(ours[..., :3] - ours[0, 0, :3]).sum(axis=-1) > 30).mean()
        assert drawn > 0.1, f"{name}: the brain is not drawn ({drawn:.1%} of pixels differ from the corner)"


def _api(port: int) -> httpx.Client:
    """A client of the server on `port`; one token for all (uploads and jobs belong to their client)."""
    return httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30, trust_env=False, headers=CLIENT)


def _healthy(client) -> bool:
    try:
        return client.get("/healthz").status_code == 200
    except httpx.HTTPError:  # not up yet
        return False


def test_serve_runs_a_job_and_keeps_it_across_a_restart(podman, image):
    name, volume, port = f"bp-test-{uuid.uuid4().hex[:8]}", f"bp-test-{uuid.uuid4().hex[:8]}", free_port()
    run([*podman, "volume", "create", volume])
    try:
        run([*podman, "run", "-d", "--name", name, "-p", f"127.0.0.1:{port}:8000", "-v", f"{volume}:/data",
             image, "serve"])
        with _api(port) as client:
            assert wait_for(lambda: _healthy(client), 180, 0.5), run([*podman, "logs", name]).stderr[-3000:]
            run([*podman, "healthcheck", "run", name])  # the image's HEALTHCHECK passes
            r = client.post("/api/uploads", params={"name": "table.csv"}, content=EXAMPLE.read_bytes(),
                            headers={"content-type": "application/octet-stream"})
            assert r.status_code == 200, r.text
            r = client.post("/api/jobs", json={"upload_id": r.json()["upload_id"], "kind": "images",
                                               "options": {"views": "lateral-left", "size": "320x240",
                                                           "gradient": "white,red"}})
            assert r.status_code == 202, r.text
            url = r.json()["url"]
            job = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j,
                           600, 1)
            assert job and job["status"] == "done", job or client.get(url).json()
            pngs = {f["name"]: f["url"] for f in job["files"] if f["name"].endswith(".png")}
            assert sorted(pngs) == [f"stage-{i}_lateral-left.png" for i in range(1, 5)]
            stage4 = png_pixels(client.get(pngs["stage-4_lateral-left.png"]).content)
            stage1 = png_pixels(client.get(pngs["stage-1_lateral-left.png"]).content)
            assert stage4.shape == (240, 320, 4)
            assert stage4[..., 1].mean() < stage1[..., 1].mean()  # stage 4 is redder on white..red
        run([*podman, "stop", "-t", "20", name], timeout=120)
        run([*podman, "start", name])
        with _api(port) as client:
            assert wait_for(lambda: _healthy(client), 180, 0.5), run([*podman, "logs", name]).stderr[-3000:]
            again = client.get(url).json()
            assert again["status"] == "done" and again["id"] == job["id"], again
            assert png_pixels(client.get(pngs["stage-4_lateral-left.png"]).content).shape == (240, 320, 4)
    finally:
        run([*podman, "rm", "-f", "-t", "5", name], check=False)
        run([*podman, "volume", "rm", "-f", volume], check=False)
