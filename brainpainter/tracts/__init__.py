"""White-matter tracts: streamlines read, resampled and oriented, their tubes, bundle names and values.

``names`` bundle names and their aliases; ``streamlines`` resampling,
orienting and subsampling of packed streamlines; ``read`` the tractogram
files (.trk, .tck, .trx) into a :class:`~brainpainter.tracts.model.Tracts`;
``tubes`` the triangle tubes a renderer draws; ``values`` bundle tables and
along-tract profiles. Everything here is numpy (and nibabel to read);
the scene model (:mod:`brainpainter.rendering.geometry`) turns tracts into parts.
"""
