"""The ``brainpainter`` console entry point: Ctrl-C and SIGTERM are handled from its first statement.

Importing the command line (click, numpy, pandas, matplotlib) takes a second
or more; a signal then used to print a ``KeyboardInterrupt`` traceback (or
die silently by SIGTERM). Until :func:`brainpainter.cli.guard.run` installs
its handlers nothing has been written, so a signal before that ends the
process at once with the usual line and exit code (130 / 143).

The handlers are installed when this module is *imported*, by its first
statement, with no import before it: ``os``, ``sys`` and ``_signal`` (the C
half of :mod:`signal`) are loaded by Python's own start-up, while ``import
signal`` would load ``enum``, ``functools`` and ``collections`` first (5 to
20 ms on a bare Python). The console script (``from brainpainter.cli.entry
import main``) and ``python -m brainpainter`` import this module first, and
only they do (the commands live in :mod:`brainpainter.cli.main`). Before it,
only ``brainpainter/__init__.py`` and ``brainpainter/cli/__init__.py`` run,
and both import nothing (``tests/test_signals.py`` checks it).

What remains is Python's own start-up up to that import: the interpreter,
``site`` (which runs every ``.pth`` file of the installed packages: an
editable install's finder, ``distutils-precedence.pth``...) and the console
script's own ``import re, sys`` (pip writes that script; ``re`` alone takes
about 18 ms on a bare, loaded Python); tens of milliseconds, measured by
``benchmarks/signal_window.py``. A SIGINT there kills the process silently
before Python has installed its own handler (status -2, 130 in a shell), and
after that raises Python's ``KeyboardInterrupt``: a traceback (seen: exit
status 1, inside ``site``'s imports). A SIGTERM kills the process (status
-15, 143 in a shell). Nothing of brainpainter has run yet, so nothing was
written either. No code of a package can run earlier than that.
"""

import os
import sys

# the signal module's C half, which Python loaded at start-up (``signal`` where it did not)
_signal = sys.modules.get("_signal") or __import__("signal")

EXIT_SIGINT = 130
EXIT_SIGTERM = 143


def _early(signum: int, frame: object) -> None:
    word, code = ("terminated", EXIT_SIGTERM) if signum == _signal.SIGTERM else ("interrupted", EXIT_SIGINT)
    try:
        os.write(2, f"{word}: nothing was published; partial output was removed\n".encode())
    except OSError:
        pass
    os._exit(code)  # nothing to clean up yet: no output, no staging folder, no temporary folder


def install_early_handlers() -> None:
    """SIGINT and SIGTERM end the process at once (until the guard takes over)."""
    try:
        _signal.signal(_signal.SIGINT, _early)
        _signal.signal(_signal.SIGTERM, _early)
    except ValueError:  # not the main thread (main() called from a thread): the caller's handlers stay
        pass


install_early_handlers()  # the first statement: see the module's docstring


def main(argv: list[str] | None = None) -> None:
    """Console entry point (``brainpainter``, ``python -m brainpainter``); see ``cli.main.main``."""
    install_early_handlers()
    from brainpainter.cli.main import main as cli_main

    cli_main(argv)
