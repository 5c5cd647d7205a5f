"""The atlas check for plugin authors: :func:`check_atlas`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .stand_in import stand_in


def check_atlas(atlas: Any, template: str | Path = "fsaverage") -> dict[str, Any]:
    """Check an atlas the way brainpainter uses it; raise AssertionError listing every problem.

    Parameters
    ----------
    atlas : str or Atlas
        Registry name (loads it through the registry, as ``--atlas NAME`` does) or an Atlas.
    template : str or path
        Template to draw it on.

    Returns
    -------
    dict
        ``atlas``, ``template``, ``label_set``, ``n_cortical`` (per hemisphere),
        ``n_subcortical``, ``n_regions_matched``, ``unmatched_columns``.
    """
    import numpy as np

    from brainpainter.atlas import registry
    from brainpainter.atlas.model import Atlas
    from brainpainter.atlas.template import load_template, template_for
    from brainpainter.rendering.run import render

    a: Atlas = registry.atlases.get(atlas) if isinstance(atlas, str) else atlas
    problems: list[str] = []
    tpl = template_for(a, load_template(template))
    if a.template_labels not in tpl.label_sets:
        raise AssertionError(f"atlas {a.name!r}: template {tpl.name!r} has no label set "
                             f"{a.template_labels!r} (it has {tpl.label_sets}) and the atlas brings none "
                             "(labels.json)")
    with_faces: set[str] = set()
    for hemi, prefix in (("lh", "Left-"), ("rh", "Right-")):
        cm = tpl.cortex(a.template_labels, hemi)
        with_faces |= {prefix + cm.label_names[i] for i in np.unique(cm.face_label).tolist()}
    subcortical = set(tpl.subcortical().label_names) if tpl.manifest.get("subcortical") else set()
    for r in a.regions:
        drawn = with_faces if r.kind == "cortical" else subcortical
        missing = [k for k in a.member_keys(r.key) if k not in drawn]
        if missing:
            problems.append(f"region {r.key!r} has nothing to draw on template {tpl.name!r} "
                            f"({', '.join(missing)} missing)")
    data = {r.key: float(i) for i, r in enumerate(a.regions)}
    with stand_in() as renderer:
        result = render(data, a, template=tpl, renderer=renderer, width=32, height=24,
                        views="lateral-left,medial-right,subcortical", progress=False)
    summary = result.manifest["input"]
    if summary["unmatched_columns"]:
        problems.append(f"region keys that do not read back as regions: {summary['unmatched_columns']}")
    if summary["n_regions_matched"] != len(a.regions):
        problems.append(f"{summary['n_regions_matched']} of {len(a.regions)} region keys matched")
    if problems:
        raise AssertionError(f"atlas {a.name!r}: " + "; ".join(problems))
    return {
        "atlas": a.name, "template": tpl.name, "label_set": a.template_labels,
        "n_cortical": {h: len(a.cortical(h)) for h in ("lh", "rh")}, "n_subcortical": len(a.subcortical()),
        "n_regions_matched": summary["n_regions_matched"], "unmatched_columns": summary["unmatched_columns"],
    }
