"""Helpers for the ``brainpainter serve`` tests: a stand-in renderer the server's processes can load."""

from __future__ import annotations

import io
import os
import time
import zipfile
from pathlib import Path

import numpy as np
from PIL import Image

from brainpainter.testing import fake_distribution

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
STANDIN = "web-stand-in"


def standin_site(root: Path) -> Path:
    """An installed distribution whose entry point names :class:`brainpainter.testing.StandInRenderer`.

    Put the returned folder on ``PYTHONPATH`` and the server's worker processes (spawned
    interpreters) find renderer ``web-stand-in`` through the real entry-point registry.
    """
    entry = {"brainpainter.renderers": {STANDIN: "brainpainter.testing:StandInRenderer"}}
    return fake_distribution(root, "bp-web-stand-in", entry, {})


def env_with_site(site: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "BRAINPAINTER_DEBUG"}
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def png_pixels(data: bytes) -> np.ndarray:
    """RGBA uint8, shape (h, w, 4)."""
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGBA"))


def zip_pngs(data: bytes) -> dict[str, np.ndarray]:
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        return {n: png_pixels(zf.read(n)) for n in zf.namelist() if n.endswith(".png")}


def wait_for(predicate, timeout: float, step: float = 0.2):
    """Call `predicate` until it returns something truthy (returned) or `timeout` seconds pass (None)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        got = predicate()
        if got:
            return got
        time.sleep(step)
    return None
