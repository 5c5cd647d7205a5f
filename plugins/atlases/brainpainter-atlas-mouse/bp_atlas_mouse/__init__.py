"""The original BrainPainter's mouse brain as a brainpainter atlas plugin.

The atlas is data (``data/mouse``): ``atlas.json`` and ``regions.tsv`` like
every atlas, plus ``template/``, a brain of its own made of the region meshes
(:mod:`brainpainter.atlas.meshfolder`). ``build_data.py`` beside this package
makes that folder from the original's PLY files.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from brainpainter.atlas.model import Atlas, load_atlas_dir

DATA = Path(str(resources.files(__name__) / "data" / "mouse"))


def mouse() -> Atlas:
    """BrainPainter's mouse brain: 20 cortical areas and 7 structures per hemisphere (Marinescu et al.)."""
    return load_atlas_dir(DATA)
