"""Fault injection through real processes: signals, kill -9, two runs at once, full and read-only disks.

Every test checks the guarantees of docs/reliability.md: one line on stderr
and the documented exit code, nothing published by a failed run, no staging
folder left by a run that could clean up, a manifest that always describes
the files beside it (0 stale manifests), and nothing written outside the
output folder. The stand-in renderer, installed as a plugin (a fake
distribution), paints noisy images or not, optionally slowly, so runs can be interrupted.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from brainpainter.testing import fake_distribution

# The stand-in renderer as an installed plugin: BP_DELAY seconds an image; BP_NOISE=1 incompressible pixels.
PLUGIN = """
import os

from brainpainter.testing import StandInRenderer

SlowRenderer = StandInRenderer.with_(delay=float(os.environ.get("BP_DELAY", "0")),
                                     noise=os.environ.get("BP_NOISE") == "1")
"""


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    site = fake_distribution(tmp_path_factory.mktemp("site"), "bp-slow",
                             {"brainpainter.renderers": {"slow": "bp_slow:SlowRenderer"}},
                             {"bp_slow.py": PLUGIN})
    base = {k: v for k, v in os.environ.items()
            if k not in ("BRAINPAINTER_DEBUG", "MPLCONFIGDIR") and not k.startswith("BLENDER_USER")}
    base["PYTHONPATH"] = os.pathsep.join([str(site), base.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return base


def table(path: Path, n: int) -> Path:
    rows = "".join(f"s{i:03d},{i % 4},{(i + 1) % 4}\n" for i in range(n))
    path.write_text("Image-name-unique,Left-insula,Right-insula\n" + rows)
    return path


def args_render(csv: Path, out: Path, tiny: Path, size: str = "32x32") -> list[str]:
    return ["render", str(csv), "--out", str(out), "--renderer", "slow", "--template", str(tiny),
            "--views", "lateral-left", "--size", size, "-q"]


def start(args: list[str], env: dict[str, str], prefix: list[str] | None = None,
          **extra: str) -> subprocess.Popen:
    return subprocess.Popen([*(prefix or []), sys.executable, "-m", "brainpainter", *args],
                            env={**env, **extra}, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(proc: subprocess.Popen, timeout: float = 300) -> tuple[int, str, str]:
    out, err = proc.communicate(timeout=timeout)
    return proc.returncode, out, err


def brainpainter(args: list[str], env: dict[str, str], prefix: list[str] | None = None,
                 **extra: str) -> tuple[int, str, str]:
    return finish(start(args, env, prefix, **extra))


def stages(folder: Path) -> list[Path]:
    if not folder.is_dir():
        return []
    return [p for p in folder.iterdir() if p.name.startswith(".brainpainter-staging-")]


def wait_for_staged_png(folder: Path, proc: subprocess.Popen, timeout: float = 120) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if any(list(s.glob("*.png")) for s in stages(folder)):
            return
        if proc.poll() is not None:
            raise AssertionError(f"the run ended early: {proc.communicate()}")
        time.sleep(0.05)
    raise AssertionError("no staged PNG appeared")


def assert_consistent(out: Path) -> dict:
    """The manifest describes exactly the files beside it: every one exists and says it is that image."""
    from PIL import Image

    manifest = json.loads((out / "manifest.json").read_text())
    for entry in manifest["files"]:
        with Image.open(out / entry["file"]) as im:
            assert im.text["brainpainter:image"] == entry["image"]
            assert json.loads(im.text["brainpainter:settings"]) == manifest["settings"]
    return manifest


def one_line(err: str, start: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(start), err
    assert "Traceback" not in err


@pytest.mark.parametrize(("sig", "code", "word"), [(signal.SIGINT, 130, "interrupted"),
                                                   (signal.SIGTERM, 143, "terminated")])
def test_signal_mid_render_publishes_nothing(tmp_path, env, tiny, sig, code, word):
    out = tmp_path / "out"
    assert brainpainter(args_render(table(tmp_path / "a.csv", 2), out, tiny), env)[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    proc = start(args_render(table(tmp_path / "b.csv", 40), out, tiny, size="48x48"), env, BP_DELAY="0.1")
    wait_for_staged_png(out, proc)
    proc.send_signal(sig)
    rc, _, err = finish(proc)
    assert rc == code, err
    one_line(err, word)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # the previous output, untouched
    assert assert_consistent(out)["input"]["n_images"] == 2


def test_kill_9_leaves_the_previous_output_and_the_next_run_cleans_up(tmp_path, env, tiny):
    out = tmp_path / "out"
    assert brainpainter(args_render(table(tmp_path / "a.csv", 2), out, tiny), env)[0] == 0
    proc = start(args_render(table(tmp_path / "b.csv", 40), out, tiny), env, BP_DELAY="0.1")
    wait_for_staged_png(out, proc)
    proc.kill()
    proc.communicate()
    assert stages(out)  # a killed process cannot clean up...
    assert assert_consistent(out)["input"]["n_images"] == 2  # ...but no manifest describes the wrong files
    rc, _, err = brainpainter(args_render(table(tmp_path / "c.csv", 3), out, tiny), env)
    assert rc == 0, err
    assert not stages(out)  # ...and the next run removes the leftovers
    assert assert_consistent(out)["input"]["n_images"] == 3


def test_two_runs_into_one_folder(tmp_path, env, tiny):
    out = tmp_path / "out"
    first = start(args_render(table(tmp_path / "a.csv", 60), out, tiny), env, BP_DELAY="0.25")
    wait_for_staged_png(out, first)
    rc, _, err = brainpainter(args_render(table(tmp_path / "b.csv", 2), out, tiny), env)
    assert first.poll() is None, "the first run ended before the second tried: make it slower"
    assert rc == 2
    one_line(err, "error: ")
    assert "in use by another brainpainter run" in err
    rc, _, err = finish(first)
    assert rc == 0, err
    manifest = assert_consistent(out)
    assert manifest["input"]["n_images"] == 60 and not stages(out)


needs_mount = pytest.mark.skipif(os.geteuid() != 0 or sys.platform != "linux",
                                 reason="mounting a small tmpfs needs root on Linux")


@pytest.fixture
def small_disk(tmpfs):
    """A 96 KB tmpfs (root only); unmounted afterwards."""
    return tmpfs("size=96k")


@needs_mount
def test_full_disk_render_is_one_line_and_publishes_nothing(small_disk, env, tiny, tmp_path):
    out = small_disk / "out"
    rc, _, err = brainpainter(args_render(table(tmp_path / "a.csv", 6), out, tiny, size="128x128"), env,
                              BP_NOISE="1")
    assert rc == 2, err
    one_line(err, "error: ")
    assert "disk is full" in err
    assert list(small_disk.iterdir()) == []  # no partial PNG, no staging folder, no empty output folder


@needs_mount
@pytest.mark.parametrize("ending", [".mp4", ".gif"])
def test_full_disk_movie_is_not_reported_as_written(small_disk, env, tiny, tmp_path, ending):
    movie = small_disk / f"m{ending}"
    csv = table(tmp_path / "a.csv", 3)
    rc, out, err = brainpainter(["movie", str(csv), "--out", str(movie), "--renderer", "slow", "--template",
                                 str(tiny), "--views", "lateral-left", "--size", "160x120",
                                 "--frames-per-step", "12", "-q"], env, BP_NOISE="1")
    assert rc == 2, (out, err)
    one_line(err, "error: ")
    assert "movie written" not in out
    assert list(small_disk.iterdir()) == []


@needs_mount
def test_read_only_data_folder(tmp_path, env):
    data = tmp_path / "data"
    data.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(data)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a read-only tmpfs here")
    try:
        config = tmp_path / "lobes.toml"
        config.write_text('[atlas]\nbase = "dk"\n[groups]\nfrontal = ["superiorfrontal"]\n')
        rc, _, err = brainpainter(["atlas", "add", "lobes", "--config", str(config)], env,
                                  XDG_DATA_HOME=str(data))
        assert rc == 2, err
        one_line(err, "error: ")
        assert "read-only" in err
        csv = table(tmp_path / "a.csv", 1)
        rc, _, err = brainpainter(["render", str(csv), "--out", str(data / "out")], env)
        assert rc == 2 and "read-only" in err
        one_line(err, "error: ")
    finally:
        subprocess.run(["umount", "-l", str(data)], check=False)


def test_read_only_output_folder(tmp_path, env, tiny, without_root_powers):
    """A folder without write permission; root runs without its capabilities, so it is refused too."""
    out = tmp_path / "out"
    out.mkdir()
    out.chmod(0o555)
    try:
        rc, _, err = brainpainter(args_render(table(tmp_path / "a.csv", 1), out, tiny), env,
                                  without_root_powers)
    finally:
        out.chmod(0o755)
    assert rc == 2 and "permission denied" in err, err
    one_line(err, "error: ")
    assert list(out.iterdir()) == []


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_full_stdout_is_one_line(env):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "brainpainter", "atlas", "list"], env=env, stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 2
    one_line(proc.stderr, "error: cannot write to standard output")


def test_nothing_written_outside_the_output_folder(tmp_path, env, tiny):
    """A figure run (matplotlib: font cache, config) writes nothing into HOME, the caches or TMPDIR but
    brainpainter's own cache folder (the installed plugins, the cortex parts, Mesa's shaders)."""
    home, tmp, work = tmp_path / "home", tmp_path / "tmp", tmp_path / "work"
    for p in (home, tmp, work):
        p.mkdir()
    csv = table(work / "a.csv", 2)
    clean = {k: v for k, v in env.items() if not k.startswith("XDG_")}
    rc, _, err = brainpainter(["figure", str(csv), "--out", str(work / "fig" / "f.png"), "--renderer", "slow",
                               "--template", str(tiny), "--views", "lateral-left", "--size", "32x32", "-q"],
                              clean, HOME=str(home), TMPDIR=str(tmp))
    assert rc == 0, err
    kept = home / ".cache" / "brainpainter"
    assert {p for p in home.rglob("*") if not p.is_relative_to(kept)} <= {home / ".cache"}
    assert list(tmp.rglob("*")) == []
    assert sorted(p.relative_to(work).as_posix() for p in work.rglob("*")) == ["a.csv", "fig", "fig/f.png"]


@pytest.mark.render
@pytest.mark.parametrize("cache", ["on", "off"])
def test_the_cache_goes_under_xdg_cache_home_and_off_writes_nothing(tmp_path, env, tiny, cache):
    """Issue 44 item 17: with XDG_CACHE_HOME set, a Blender render made ``$XDG_CACHE_HOME/thumbnails/``
    (the user's own variable was left to the libraries), also with BRAINPAINTER_CACHE=off; now the cache is
    ``$XDG_CACHE_HOME/brainpainter`` and nothing else, and off writes nothing outside the output."""
    home, xdg, tmp, work = (tmp_path / name for name in ("home", "xdg", "tmp", "work"))
    for p in (home, xdg, tmp, work):
        p.mkdir()
    csv = table(work / "a.csv", 1)
    clean = {k: v for k, v in env.items() if not k.startswith("XDG_") and k != "BRAINPAINTER_CACHE"}
    extra = {"HOME": str(home), "TMPDIR": str(tmp), "XDG_CACHE_HOME": str(xdg)}
    if cache == "off":
        extra["BRAINPAINTER_CACHE"] = "off"
    rc, _, err = brainpainter(["render", str(csv), "--out", str(work / "out"), "--template", str(tiny),
                               "--views", "dorsal", "--size", "64x48", "-q"], clean, **extra)
    assert rc == 0, err
    assert list(home.rglob("*")) == [] and list(tmp.rglob("*")) == []
    written = sorted(p.relative_to(xdg).as_posix() for p in xdg.rglob("*"))
    if cache == "off":
        assert written == []
    else:
        assert "brainpainter/entry-points.json" in written
        assert all(p == "brainpainter" or p.startswith("brainpainter/") for p in written), written
    assert sorted(p.relative_to(work).as_posix() for p in work.rglob("*")) == [
        "a.csv", "out", "out/manifest.json", "out/s000_dorsal.png"]
