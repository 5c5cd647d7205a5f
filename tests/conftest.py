"""Shared fixtures: isolated HOME/caches, paths to ../shared/data."""

from __future__ import annotations

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
def fsaverage5() -> Path:
    path = FREESURFER / "subjects" / "fsaverage5"
    if not path.is_dir():
        pytest.skip(f"shared data not found at {path} (needs ../shared/data beside the repo)")
    return path
