"""Bundle names: one canonical spelling per bundle, whatever tool wrote it.

TractSeg writes ``AF_left``, pyAFQ ``ARC_L`` or ``Left Arcuate``, dipy's BUAN
``AF_L``; all become ``AF_left``. The alias table is data
(``brainpainter/data/bundle_names.tsv``); a name it does not know is kept,
with its hemisphere spelled ``_left``/``_right``.
"""

from __future__ import annotations

import re
from functools import cache
from importlib import resources

from brainpainter.atlas.model import hemisphere_in_name

#: Prefix of a bundle's palette keys (``tract:AF_left``), apart from region keys.
KEY_PREFIX = "tract:"

_HEMI = {"lh": "left", "rh": "right"}


def _fold(text: str) -> str:
    return re.sub(r"[^a-z0-9]", "", text.lower())


@cache
def _aliases() -> dict[str, str]:
    """Folded spelling -> canonical hemisphere-free name."""
    text = resources.files("brainpainter.data").joinpath("bundle_names.tsv").read_text("utf-8")
    out: dict[str, str] = {}
    rows = [line.split("\t") for line in text.splitlines() if line and not line.startswith("#")]
    for name, aliases, *_ in rows[1:]:
        for spelling in (name, *aliases.split("|")):
            out[_fold(spelling)] = name
    return out


def split_hemisphere(name: str) -> tuple[str, str | None]:
    """``("AF", "left")`` for ``AF_L``, ``Left Arcuate``, ``lh.AF``; ``(name, None)`` without one."""
    hemi, rest = hemisphere_in_name(name)  # the atlases' rule
    return rest, _HEMI.get(hemi or "")


def canonical(name: str) -> str:
    """The canonical bundle name: ``AF_left`` for ``ARC_L``, ``CC_ForcepsMajor`` for ``Forceps Major``.

    The whole name is looked up first (so ``CC_ForcepsMajor`` keeps its
    ``CC``), then the name without its hemisphere.
    """
    text = str(name).strip()
    whole = _aliases().get(_fold(text))
    if whole is not None:
        return whole
    base, hemi = split_hemisphere(text)
    base = _aliases().get(_fold(base), re.sub(r"[\s.-]+", "_", base))
    return f"{base}_{hemi}" if hemi else base


def hemisphere(name: str) -> str | None:
    """``"lh"``, ``"rh"`` or None (commissural, midline, or unknown) of a canonical bundle name."""
    if name.endswith("_left"):
        return "lh"
    if name.endswith("_right"):
        return "rh"
    return None


def bundle_key(name: str, node: int | None = None) -> str:
    """Palette key of a bundle (``tract:AF_left``) or of one of its nodes (``tract:AF_left:17``)."""
    return f"{KEY_PREFIX}{name}" if node is None else f"{KEY_PREFIX}{name}:{node}"
