"""Importing brainpainter and running --help never import bpy."""

from __future__ import annotations

import subprocess
import sys


def _modules_after(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys; print('\\n'.join(sys.modules))"],
                         capture_output=True, text=True, check=True)
    return set(out.stdout.split())


def test_import_does_not_import_bpy_or_heavy_modules():
    mods = _modules_after("import brainpainter")
    assert "bpy" not in mods
    assert not {"pandas", "matplotlib", "nibabel", "pymeshlab"} & mods


def test_help_does_not_import_bpy():
    code = ("import sys\nfrom brainpainter.cli.main import main\nsys.argv=['brainpainter','--help']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass")
    mods = _modules_after(code)
    assert "bpy" not in mods
    assert "pandas" not in mods


def test_atlas_list_does_not_import_bpy():
    code = ("import sys\nfrom brainpainter.cli.main import main\nsys.argv=['brainpainter','atlas','list']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass")
    assert "bpy" not in _modules_after(code)
