"""pytest fixtures for plugin test suites (``pytest_plugins = ["brainpainter.testing"]``)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from .stand_in import stand_in


@pytest.fixture
def brainpainter_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """HOME and XDG folders in `tmp_path`: user atlases go there, never to the real home.

    Returns the (not yet created) user-atlas folder.
    """
    from brainpainter.atlas import registry
    from brainpainter.atlas.registry import atlases_dir

    home = tmp_path / "home"
    monkeypatch.setenv("HOME", str(home))
    for var, sub in (("XDG_DATA_HOME", ".local/share"), ("XDG_CACHE_HOME", ".cache"),
                     ("XDG_CONFIG_HOME", ".config")):
        monkeypatch.setenv(var, str(home / sub))
    registry.reset_all()
    yield atlases_dir()
    registry.reset_all()


@pytest.fixture
def stand_in_renderer() -> Iterator[str]:
    """Name of a registered :class:`~brainpainter.testing.StandInRenderer` (renders without Blender)."""
    with stand_in() as name:
        yield name
