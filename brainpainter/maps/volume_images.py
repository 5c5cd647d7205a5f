"""A volume as named images and as a region table: :func:`volume_images`, :func:`subcortical_table`.

The images of an MNI152 volume projected onto fsaverage (:func:`brainpainter.maps.volume.project_volume`)
and the means inside the subcortical structures (:func:`brainpainter.maps.volume.subcortical_means`),
named alike (the file's name; ``"{file}_{index}"`` for each volume of a 4-D file), so that the two
colour the same images.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from brainpainter.maps.volume import ImageLike, Method, load_volume, project_volume, subcortical_means


def volume_images(path: ImageLike, *, method: Method = "linear"
                  ) -> list[tuple[str, dict[str, NDArray[np.float32]]]]:
    """The images of a volume file projected onto fsaverage, one per volume, named.

    Parameters
    ----------
    path : path or nibabel image
        An MNI152 volume, 3-D or 4-D.
    method : {"linear", "nearest"}
        As in :func:`project_volume`.

    Returns
    -------
    list of (str, dict)
        ``[(name, {"lh": ndarray (163842,), "rh": ndarray (163842,)}), ...]``: one entry named
        after the file (``"zstat1"``) for a 3-D volume; for a 4-D one, one per volume, named
        ``"{file}_{index}"`` with the index from 0, zero-padded (``"bold_000"``).
    """
    volume = load_volume(path)
    maps = project_volume(path, method=method)
    if len(volume.shape) == 3:
        return [(volume.name, maps)]
    return [(name, {hemi: m[i] for hemi, m in maps.items()}) for i, name in enumerate(volume.image_names)]


def subcortical_table(img: ImageLike, *, method: Method = "linear") -> dict[str, dict[str, float]]:
    """:func:`subcortical_means` as a region table: ``{image: {structure: mean}}``.

    The images are named as in :func:`volume_images` (the file's name; ``"{file}_{index}"`` for
    each volume of a 4-D file), so ``brainpainter.read_table(subcortical_table(path), "dk")``
    colours the subcortical structures of the same images the cortex maps show. Structures the
    volume does not reach (NaN) are left out.

    Parameters
    ----------
    img : path or nibabel image
        An MNI152 volume, 3-D or 4-D.
    method : {"linear", "nearest"}
        As in :func:`subcortical_means`.

    Returns
    -------
    dict
        ``{"zstat1": {"Left-Hippocampus": 2.1, ...}}``, one entry per image.
    """
    volume = load_volume(img)
    means = subcortical_means(img, method=method)
    if len(volume.shape) == 3:
        return {volume.name: {k: float(v) for k, v in means.items() if np.isfinite(v)}}
    return {name: {k: float(np.asarray(v)[i]) for k, v in means.items() if np.isfinite(np.asarray(v)[i])}
            for i, name in enumerate(volume.image_names)}
