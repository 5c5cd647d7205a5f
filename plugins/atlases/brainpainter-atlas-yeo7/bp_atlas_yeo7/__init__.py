"""The Yeo 2011 7-network atlas as a brainpainter atlas plugin.

The atlas is data (``data/yeo7``): ``atlas.json`` and ``regions.tsv`` like the
built-in atlases, plus a label-set overlay for the bundled fsaverage template
(``labels.json`` and ``cortex-{lh,rh}-yeo7.npz``: one network label per face
of the template's cortex mesh). ``build_data.py`` beside this package makes
that folder from FreeSurfer's ``?h.Yeo2011_7Networks_N1000.annot``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from brainpainter.atlas.model import Atlas, load_atlas_dir

DATA = Path(str(resources.files(__name__) / "data" / "yeo7"))


def yeo7() -> Atlas:
    """Yeo et al. (2011) 7 resting-state networks per hemisphere, plus aseg subcortical structures."""
    return load_atlas_dir(DATA)
