"""Helpers for testing brainpainter and its plugins (usable from any pytest suite).

* :class:`StandInRenderer` (``stand_in.py``): a renderer without Blender, with
  parameters for what tests need (layouts, delays, failures, leaks);
  :func:`stand_in` and :func:`registered_renderer` register one for a block.
* :func:`write_tiny_template` and :func:`write_template` (``templates.py``):
  synthetic templates written in the template format.
* :func:`fake_distribution`, :func:`installed`, :func:`pip_install`
  (``distributions.py``): installed plugin distributions for registry tests.
* :func:`check_atlas` (``atlas_check.py``) and :func:`check_renderer`
  (``conformance.py``): the checks an atlas or renderer plugin must pass.
* :func:`growth_per_image` (``memory.py``): resident memory growth per image.
* ``brainglobe.write_format3_atlas``: a BrainGlobe atlas in format 3 (as
  brainglobe-atlasapi 3 reads it) in a folder, without network (import it from
  :mod:`brainpainter.testing.brainglobe`; it needs zarr and DracoPy).

For atlas plugin authors: :func:`check_atlas` runs every check brainpainter
makes of an atlas using :class:`StandInRenderer`. In a plugin's
``tests/conftest.py``::

    pytest_plugins = ["brainpainter.testing"]   # fixtures: brainpainter_home, stand_in_renderer

and in a test::

    from brainpainter.testing import check_atlas

    def test_my_atlas(brainpainter_home):
        report = check_atlas("myatlas")
        assert report["n_cortical"] == {"lh": 7, "rh": 7}
"""

from __future__ import annotations

import sys

from .atlas_check import check_atlas
from .conformance import CONFORMANCE_CHECKS, check_renderer
from .distributions import fake_distribution, installed, pip_install
from .memory import growth_per_image, rss_mb, theil_sen
from .stand_in import StandInRenderer, band_edges, registered_renderer, stand_in
from .templates import CortexMesh, Structure, write_template, write_tiny_template

__all__ = [
    "CONFORMANCE_CHECKS", "CortexMesh", "StandInRenderer", "Structure", "band_edges", "check_atlas",
    "check_renderer", "fake_distribution", "growth_per_image", "installed", "pip_install",
    "registered_renderer", "rss_mb", "stand_in", "theil_sen", "write_template", "write_tiny_template",
]

if "pytest" in sys.modules:  # fixtures for plugin test suites: pytest_plugins = ["brainpainter.testing"]
    # (a process that only loads the stand-in renderer, e.g. as an installed plugin, does not import pytest)
    from .fixtures import brainpainter_home, stand_in_renderer

    __all__ += ["brainpainter_home", "stand_in_renderer"]
