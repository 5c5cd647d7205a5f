"""A real ``brainpainter serve`` on 127.0.0.1 for the serve benchmarks (``bench_serve.py``,
``bench_serve_attack.py``); not a benchmark itself."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Serve:
    """``brainpainter serve --data-dir data *options`` on a free port (or `port`), ready when made.

    :meth:`start` starts it again (after a kill) on the same port and data folder; ``ready_s`` is
    how long the last start took until ``/readyz`` answered. Its output goes to
    ``serve-PORT.log`` beside the data folder.
    """

    def __init__(self, data: Path, *options: str, port: int | None = None) -> None:
        self.data, self.options = data, options
        self.port = port or free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.start()

    def start(self) -> None:
        self.log = (self.data.parent / f"serve-{self.port}.log").open("a")
        self.proc = subprocess.Popen([sys.executable, "-m", "brainpainter", "serve", "--port", str(self.port),
                                      "--data-dir", str(self.data), "--log-level", "warning", *self.options],
                                     stdout=self.log, stderr=subprocess.STDOUT)
        t0 = time.perf_counter()
        for _ in range(2400):
            try:
                if httpx.get(f"{self.url}/readyz", timeout=2).status_code == 200:
                    self.ready_s = time.perf_counter() - t0
                    return
            except httpx.HTTPError:
                pass
            if self.proc.poll() is not None:
                raise SystemExit(f"server exited; see {self.log.name}")
            time.sleep(0.25)
        raise SystemExit("server not ready in 10 minutes")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
