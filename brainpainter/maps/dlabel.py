"""A CIFTI-2 label file as the label maps of a region atlas (``atlas add NAME --dlabel FILE``).

The file is read as every CIFTI map is (:func:`~brainpainter.maps.inputs.read_maps`:
its label table's names and colours) and each hemisphere's labels are brought to the
surface the template was built from: fsLR 32k and 164k onto fsaverage by nearest vertex
through HCP's deformed spheres (:mod:`brainpainter.maps.fslr`), the coarser fsaverage
meshes by their parents (:mod:`brainpainter.maps.resolution`); a template built from a
subject takes labels of its own vertex count as they are. The label names are the
regions' names (Schaefer's ``7Networks_LH_Vis_1``), the CIFTI structure
(``CORTEX_LEFT``/``CORTEX_RIGHT``) their hemisphere, the label colours theirs; the medial
wall, ``???`` and vertices absent from the file are unlabelled. The file's subcortical
voxels are not used (a note says so): the atlas has the template's aseg structures.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.atlas.labelset import LabelMap, is_non_region, label_map, source_vertex_count
from brainpainter.atlas.template import HEMIS, Template
from brainpainter.errors import BrainPainterError
from brainpainter.maps.cifti import CIFTI_SUFFIXES, CONNECTOMES
from brainpainter.maps.inputs import read_maps
from brainpainter.maps.resolution import N_FSAVERAGE


def dlabel_label_maps(path: str | Path, template: Template, space: str | None = None
                      ) -> tuple[dict[str, LabelMap], tuple[str, ...]]:
    """One label map per hemisphere from a CIFTI-2 ``.dlabel.nii``, on `template`'s source surface.

    Parameters
    ----------
    path : path
        A dlabel with one label map and both cortex structures.
    template : Template
        The fsaverage template (labels resampled onto its 163,842 vertices), or one built
        from a subject (labels of its own vertex count, taken as they are).
    space : {"fsaverage", "fsLR"}, optional
        The mesh of a 163,842-vertex file that does not say (``--space``).

    Returns
    -------
    (dict of {"lh", "rh"} to LabelMap, tuple of str)
        ``labels`` of shape (n_source_vertices,) indexing the file's label names; and notes.

    Raises
    ------
    BrainPainterError
        Not a dlabel (a dscalar ...), a CIFTI-1 file, several label maps, a hemisphere
        missing, or label names that collide (one name in two colours, or differing in case only).
    """
    p = Path(path).expanduser()
    low = p.name.lower()
    if not low.endswith(".dlabel.nii"):
        kind = next((s[1:] for s in (*CIFTI_SUFFIXES, *CONNECTOMES) if low.endswith(s)), None)
        what = f"a CIFTI {kind} file, which holds values, not labels" if kind else "not a CIFTI label file"
        raise BrainPainterError(f"--dlabel takes a CIFTI-2 label file (.dlabel.nii); {p.name!r} is {what}. "
                                "Give a .dlabel.nii, or label maps per hemisphere with --annot.")
    counts = {h: source_vertex_count(template, h) for h in HEMIS}
    maps = read_maps(p, space=space, mesh=None if set(counts.values()) == {N_FSAVERAGE} else counts)
    what = f"CIFTI file {p.name!r}"
    if maps.categories is None or maps.category_colors is None:
        raise BrainPainterError(f"{what} has no label table (its rows are not a LabelAxis); give a dlabel "
                                "written with its labels (wb_command -cifti-label-import).")
    if maps.n_images != 1:
        raise BrainPainterError(
            f"{what} holds {maps.n_images} label maps ({', '.join(maps.images[:4])}); an atlas is one: "
            f"take one out with wb_command -cifti-merge OUT.dlabel.nii -cifti {p.name} -column N.")
    missing = [h for h in HEMIS if h not in maps.values]
    if missing:
        raise BrainPainterError(f"{what} has no {'CORTEX_LEFT' if missing[0] == 'lh' else 'CORTEX_RIGHT'} "
                                "labels; an atlas needs both hemispheres' cortex.")
    voxels = _check_label_table(p, what)
    colors = np.rint(255 * np.asarray(maps.category_colors, float)).astype(np.int64)
    out = {}
    for hemi in HEMIS:
        row = maps.on_surface(hemi, 0)
        labels = np.where(np.isfinite(row), np.nan_to_num(row, nan=-1.0), -1.0).astype(np.int64)
        out[hemi] = label_map(hemi, p, labels, list(maps.categories), colors)
    notes = maps.notes
    if voxels:
        notes += (f"the {voxels} subcortical voxels of {p.name} are not used: the atlas has the template's "
                  "subcortical structures (aseg).",)
    return out, notes


def _check_label_table(path: Path, what: str) -> int:
    """Refuse a label name given to two keys in different colours; the count of subcortical voxels.

    Read from the header's index maps (nibabel's axes of a 164k file take a second more).
    """
    import nibabel as nib

    img: Any = nib.load(str(path))
    matrix = img.header.matrix
    table = next(iter(matrix.get_index_map(0).named_maps)).label_table
    seen: dict[str, tuple[int, tuple[float, ...]]] = {}
    for key, label in sorted(table.items()):
        name, rgb = str(label.label), tuple(round(float(c), 3) for c in label.rgba[:3])
        if is_non_region(name):
            continue
        first, first_rgb = seen.setdefault(name, (int(key), rgb))
        if first_rgb != rgb:
            raise BrainPainterError(
                f"{what}: label keys {first} and {key} are both named {name!r} but in different colours, "
                "so they would be one region; give each label its own name in the label table.")
    return sum(int(m.index_count) for m in matrix.get_index_map(1).brain_models
               if m.model_type == "CIFTI_MODEL_TYPE_VOXELS")
