"""brainpainter's own readers, registered in its ``pyproject.toml`` (``brainpainter.readers``) as a
plugin registers its own: a region table, a surface map, a volume, a CIFTI file, a tractogram, a
connectivity matrix and a nodes file (:class:`~brainpainter.layers.readers.Reader`)."""

from __future__ import annotations

from typing import Any

from brainpainter.io.sniff import CURV, GIFTI, MGH, NIFTI1, NIFTI2, NPY, TCK, TRK
from brainpainter.layers.readers import Reader
from brainpainter.maps.cifti import CIFTI_SUFFIXES
from brainpainter.maps.inputs import TABLE_SUFFIXES
from brainpainter.tracts.model import SUFFIXES as TRACT_SUFFIXES
from brainpainter.tracts.model import TractSpec

table = Reader("table", "regions", "a table of values per region (CSV, TSV, text, Excel, JSON)",
               suffixes=TABLE_SUFFIXES, read="brainpainter.table.region_table:read_table", fallback=True)
surface_map = Reader("surface-map", "map", "a map per vertex of one hemisphere (FreeSurfer curv, MGH, "
                     "GIfTI, .annot, .label, .npy)",
                     suffixes=(".mgh", ".mgz", ".gii", ".gii.gz", ".npy", ".annot", ".label"),
                     magic=(CURV, MGH, GIFTI, NPY), read="brainpainter.maps.inputs:read_maps",
                     names="brainpainter.maps.inputs:is_morph_name")
volume = Reader("volume", "map", "an MNI152 volume (NIfTI), projected onto the surface",
                suffixes=(".nii", ".nii.gz"), magic=(NIFTI1, NIFTI2),
                read="brainpainter.maps.inputs:read_volume")
cifti = Reader("cifti", "map", "a CIFTI-2 file (dscalar, dlabel, pscalar, dtseries, ptseries)",
               suffixes=CIFTI_SUFFIXES, read="brainpainter.maps.inputs:read_maps")
tractogram = Reader("tractogram", "tracts", "a tractogram (TrackVis .trk, MRtrix .tck, TRX .trx)",
                    suffixes=TRACT_SUFFIXES, magic=(TRK, TCK),
                    read="brainpainter.layers.builtin_readers:tract_spec")
matrix = Reader("matrix", "connectome", "a connectivity matrix (text, .npy, .mat, CIFTI .pconn.nii, "
                "BrainNet .edge)", suffixes=(".npy", ".mat", ".edge", ".pconn.nii", ".dconn.nii"),
                read="brainpainter.connectome.matrix:read_matrix")
nodes = Reader("nodes", "connectome", "node coordinates (BrainNet Viewer .node)", suffixes=(".node",),
               read="brainpainter.connectome.nodefiles:read_nodes")


def tract_spec(path: str, **options: Any) -> TractSpec:
    """The tractograms of `path` (a file or a folder of them) to draw, with the ``--tracts-*`` `options`."""
    return TractSpec((str(path),), **options)
