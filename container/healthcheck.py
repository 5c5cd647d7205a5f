"""The image's HEALTHCHECK: GET /healthz of ``brainpainter serve`` in this container.

A container that runs another command (``render``, ``figure``, ...) has no server: it counts as healthy.
The port is ``BRAINPAINTER_SERVE_PORT`` (default 8000), the one ``serve`` listens on.
"""

import os
import sys
import urllib.request


def main() -> int:
    try:
        with open("/proc/1/cmdline", "rb") as f:
            argv = f.read().split(b"\0")
    except OSError:
        argv = []
    if b"serve" not in argv:
        return 0
    port = os.environ.get("BRAINPAINTER_SERVE_PORT", "8000")
    opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))  # never through a proxy
    try:
        with opener.open(f"http://127.0.0.1:{port}/healthz", timeout=4) as response:
            return 0 if response.status == 200 else 1
    except OSError as exc:
        print(f"healthz: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
