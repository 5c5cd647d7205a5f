"""The ``brainpainter`` console entry point: Ctrl-C and SIGTERM are handled from the first moment.

Importing the command line (click, numpy, pandas, matplotlib) takes a second
or more; a signal then used to print a ``KeyboardInterrupt`` traceback (or
die silently by SIGTERM). Until :func:`brainpainter.cli.guard.run` installs
its handlers nothing has been written, so a signal before that ends the
process at once with the usual line and exit code (130 / 143).
"""

from __future__ import annotations

import os
import signal
import threading
from typing import Any

EXIT_SIGINT = 130
EXIT_SIGTERM = 143


def _early(signum: int, frame: Any) -> None:
    word, code = ("terminated", EXIT_SIGTERM) if signum == signal.SIGTERM else ("interrupted", EXIT_SIGINT)
    try:
        os.write(2, f"{word}: nothing was published; partial output was removed\n".encode())
    except OSError:
        pass
    os._exit(code)  # nothing to clean up yet: no output, no staging folder, no temporary folder


def install_early_handlers() -> None:
    """SIGINT and SIGTERM end the process at once (until the guard takes over)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _early)
        signal.signal(signal.SIGTERM, _early)


def main(argv: list[str] | None = None) -> None:
    """Console entry point (``brainpainter``, ``python -m brainpainter``); see ``cli.main.main``."""
    install_early_handlers()
    from brainpainter.cli.main import main as cli_main

    cli_main(argv)
