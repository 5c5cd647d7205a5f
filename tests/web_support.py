"""Helpers for the ``brainpainter serve`` tests: a stand-in renderer the server's processes can load."""

from __future__ import annotations

import io
import os
import signal
import socket
import subprocess
import sys
import time
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from brainpainter.testing import fake_distribution

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
STANDIN = "web-stand-in"
#: A script's client token (docs/serve.md): connections that send it share their uploads and jobs.
CLIENT = {"x-brainpainter-client": "web-support-client-0123456789abcdef"}


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


@contextmanager
def standin_app(site: Path, data_dir: Path, **config: Any) -> Iterator[Any]:
    """A running app (a ``TestClient``, ready) drawing with the stand-in renderer of `site`.

    The server's processes find the renderer through ``PYTHONPATH``; `config` are
    :class:`~brainpainter.web.config.ServerConfig` fields (``renderer`` defaults to the stand-in).
    """
    import pytest
    from fastapi.testclient import TestClient

    from brainpainter.atlas import registry
    from brainpainter.web.app import create_app
    from brainpainter.web.config import ServerConfig

    mp = pytest.MonkeyPatch()
    for k, v in env_with_site(site).items():
        mp.setenv(k, v)
    sys.path.insert(0, str(site))
    registry.reset_all()
    try:
        app = create_app(ServerConfig(data_dir=data_dir, **{"renderer": STANDIN, **config}))
        with TestClient(app) as client:
            assert wait_for(lambda: client.get("/readyz").status_code == 200, 120), client.get("/readyz").text
            yield client
    finally:
        sys.path.remove(str(site))
        registry.reset_all()
        mp.undo()


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


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (exited, not yet reaped by init) counts as gone
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except OSError:
        return False


class Server:
    """``python -m brainpainter serve`` on a free loopback port, killable and restartable."""

    def __init__(self, data_dir: Path, env: dict[str, str], log: Path, options: list[str]) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.args = [sys.executable, "-m", "brainpainter", "serve", "--host", "127.0.0.1", "--port",
                     str(self.port), "--data-dir", str(data_dir), "--log-level", "warning", *options]
        self.env, self.log, self.proc = env, log, None

    def start(self, timeout: float = 90) -> None:
        with self.log.open("a") as fh:
            self.proc = subprocess.Popen(self.args, env=self.env, stdout=fh, stderr=subprocess.STDOUT)
        ok = wait_for(lambda: self._ready(), timeout, 0.3)
        assert ok, self.log.read_text()[-3000:]

    def _ready(self) -> bool:
        import httpx

        assert self.proc.poll() is None, self.log.read_text()[-3000:]
        try:
            return httpx.get(f"{self.url}/readyz", timeout=2).status_code == 200
        except httpx.HTTPError:
            return False

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(timeout=30)

    def stop(self) -> None:
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10)
