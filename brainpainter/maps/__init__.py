"""Per-vertex maps: values on the cortex surface, read, brought to fsaverage and composited to colours.

* :mod:`~brainpainter.maps.inputs`: files and arrays to per-hemisphere value arrays
  (:func:`~brainpainter.maps.inputs.read_maps`, the one entry for every map input).
* :mod:`~brainpainter.maps.resolution`: the fsaverage family (fsaverage3..fsaverage),
  coarse data onto fsaverage by the icosahedral subdivision.
* :mod:`~brainpainter.maps.layers`: underlay, threshold, medial wall and colour scale to per-vertex colours.
* :mod:`~brainpainter.maps.options`: ``--lh/--rh/--underlay/--threshold``.
* :mod:`~brainpainter.maps.volume`: MNI152 volumes projected onto fsaverage (registration fusion),
  :mod:`~brainpainter.maps.regfusion` its shipped data, :mod:`~brainpainter.maps.depth` sampling between
  a subject's white and pial surfaces.
"""
