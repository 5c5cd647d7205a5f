"""The commands that installed distributions add through an entry-point group, found without
:mod:`importlib.metadata`.

Importing :mod:`importlib.metadata` costs ~40 ms (it loads the ``email`` package to parse
``METADATA`` files), a third of the budget of ``brainpainter --help``, which lists the plugins'
commands. The commands need only the ``entry_points.txt`` files, so this reads them with
:mod:`configparser` from every ``*.dist-info`` and ``*.egg-info`` folder on ``sys.path`` (what pip,
editable installs and setuptools write); as in :mod:`importlib.metadata`, the first distribution
of a name on ``sys.path`` wins. ``brainpainter plugins`` still lists them through
:mod:`importlib.metadata` (with their distributions), and ``tests/test_cli_lazy.py`` checks that
both find the same commands.
"""

from __future__ import annotations

import configparser
import importlib
import os
import re
import sys
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class CommandEntry:
    """One entry point: ``name = module:attribute``."""

    name: str
    value: str

    def load(self) -> Any:
        """Import the module and return the attribute (as ``EntryPoint.load``)."""
        module, _, attr = self.value.partition(":")
        obj: Any = importlib.import_module(module.strip())
        for part in filter(None, attr.strip().split(".")):
            obj = getattr(obj, part)
        return obj


def _distribution(folder: str) -> str:
    """``My_Pkg-1.0.dist-info`` -> ``my-pkg`` (the normalised name, PEP 503)."""
    return re.sub(r"[-_.]+", "-", folder.rsplit(".", 1)[0].split("-")[0]).lower()


def entry_points(group: str) -> dict[str, CommandEntry]:
    """The entry points of `group` of the distributions on ``sys.path``, by name."""
    seen: set[str] = set()
    found: dict[str, CommandEntry] = {}
    for entry in sys.path:
        root = entry or "."
        try:
            names = sorted(os.listdir(root))
        except OSError:  # a zip file, a missing folder
            continue
        for name in names:
            if not name.endswith((".dist-info", ".egg-info")):
                continue
            dist = _distribution(name)
            if dist in seen:
                continue
            seen.add(dist)
            path = os.path.join(root, name, "entry_points.txt")
            if not os.path.isfile(path):
                continue
            parser = configparser.ConfigParser(delimiters=("=",), interpolation=None)
            parser.optionxform = str  # type: ignore[assignment,method-assign]
            try:
                parser.read(path, encoding="utf-8")
            except configparser.Error:  # a broken file: importlib.metadata would fail on it too
                continue
            if parser.has_section(group):
                for key, value in parser.items(group):
                    found.setdefault(key, CommandEntry(key, value))
    return found
