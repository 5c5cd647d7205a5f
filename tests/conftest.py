"""Shared fixtures: isolated HOME/caches, paths to ../shared/data, big corpus files written once."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"
FREESURFER = SHARED_DATA / "freesurfer"
EXAMPLES = REPO / "examples"


@pytest.fixture(autouse=True)
def _isolated_home(tmp_path_factory, monkeypatch):
    """Never touch the real user's home, config or caches."""
    home = tmp_path_factory.mktemp("home")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("XDG_DATA_HOME", str(home / ".local" / "share"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(home / ".cache"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home / ".config"))
    monkeypatch.delenv("BRAINPAINTER_DEBUG", raising=False)


@pytest.fixture
def without_root_powers() -> list[str]:
    """Command prefix that makes a process obey file permissions, also when the tests run as root.

    Root ignores permission bits through its capabilities (CAP_DAC_OVERRIDE); ``setpriv`` starts
    the command as root without any capability, so a folder without write permission refuses it
    too. Empty for other users.
    """
    if os.geteuid() != 0:
        return []
    if shutil.which("setpriv") is None:
        pytest.skip("running as root without setpriv (util-linux) to drop root's capabilities")
    return ["setpriv", "--inh-caps=-all", "--bounding-set=-all", "--"]


@pytest.fixture
def tmpfs(tmp_path) -> Iterator[Callable[[str], Path]]:
    """``tmpfs(options)``: a tmpfs mounted with `options` (``"size=96k"``, ``"ro,size=64k"``) on a new
    folder of `tmp_path` (root on Linux only: the test is skipped elsewhere); all unmounted afterwards."""
    import subprocess
    import sys

    if os.geteuid() != 0 or sys.platform != "linux":
        pytest.skip("mounting a small tmpfs needs root on Linux")
    mounted: list[Path] = []

    def mount(options: str) -> Path:
        disk = tmp_path / f"disk{len(mounted)}"
        disk.mkdir()
        if subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(disk)],
                          capture_output=True).returncode != 0:
            pytest.skip("cannot mount a tmpfs here")
        mounted.append(disk)
        return disk

    yield mount
    for disk in mounted:
        subprocess.run(["umount", "-l", str(disk)], check=False)


@pytest.fixture
def fresh_registry() -> Iterator[None]:
    """Atlases, renderers and templates are found anew before the test and forgotten after it.

    For tests that install plugins or add atlases (into their own temporary home); a module of
    them says ``pytestmark = pytest.mark.usefixtures("fresh_registry")``.
    """
    from brainpainter.atlas import registry

    registry.reset_all()
    yield
    registry.reset_all()


@pytest.fixture(scope="module")
def site(request, tmp_path_factory) -> Path:
    """The test module's plugin distribution (its ``PLUGIN`` folder) as pip installs it, into a
    throw-away site-packages folder; made once per module (use it with ``installed(site)``)."""
    from brainpainter.testing import pip_install

    return pip_install(request.module.PLUGIN, tmp_path_factory.mktemp("site"), tmp_path_factory.mktemp("src"))


@pytest.fixture
def fsaverage5() -> Path:
    path = FREESURFER / "subjects" / "fsaverage5"
    if not path.is_dir():
        pytest.skip(f"shared data not found at {path} (needs ../shared/data beside the repo)")
    return path


@pytest.fixture(scope="session")
def tiny(tmp_path_factory) -> Path:
    """The tiny synthetic template (:func:`brainpainter.testing.write_tiny_template`), written once.

    Shared by every test that asks for it: read it, never change it (a test that changes a
    template writes its own).
    """
    from brainpainter.testing import write_tiny_template

    return write_tiny_template(tmp_path_factory.mktemp("tpl") / "tiny")


@pytest.fixture(scope="session")
def big_files(tmp_path_factory) -> dict:
    """The bad-input corpus's large files, written once per session: ``{writer: path}``.

    ``corpus.write(case, folder, big_files)`` hard-links them into a case folder
    instead of writing 50 MB again (the corpus, the upload path and the memory test share one).
    """
    from bad_inputs import corpus

    path = tmp_path_factory.mktemp("big") / "50mb.csv"
    corpus._big_table(path)
    return {corpus._big_table: path}


@pytest.fixture
def glass_draws(monkeypatch) -> list[str]:
    """The glass sides each ``GpuDraw._draw_glass`` call draws (``"FRONT"``, ``"BACK"``, ``"FRONTBACK"``),
    in order; every glass is kept in layers (a tiny template's has fewer triangles than
    ``glass_layers.MIN_TRIANGLES``)."""
    from brainpainter_blender import glass_layers
    from brainpainter_blender.gpu_draw import GpuDraw

    drawn: list[str] = []
    draw_glass = GpuDraw._draw_glass

    def counted(self, aim, tex, culled, mark):
        drawn.append("".join(culled))
        return draw_glass(self, aim, tex, culled, mark)

    monkeypatch.setattr(GpuDraw, "_draw_glass", counted)
    monkeypatch.setattr(glass_layers, "MIN_TRIANGLES", 0)
    return drawn
