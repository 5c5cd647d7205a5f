"""Subcortical meshes of a FreeSurfer subject: the aseg structures of ``data/aseg.tsv``.

The meshing itself (marching cubes, Taubin smoothing, decimation, volume
matching) is the core's :mod:`brainpainter.atlas.meshing`, shared with
volumetric user atlases; this module names the structures and reads their
table (FreeSurferColorLUT indices).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from brainpainter.atlas import meshing
from brainpainter.atlas.mesh import vertex_normals
from brainpainter.atlas.meshing import (
    BLUR_KEEP,
    BLUR_VOXELS,
    DECIMATION_FRACTIONS,
    Structure,
    blur_for,
    merge_structures,
    mesh_mask,
)
from brainpainter.atlas.model import Region, read_regions_tsv

# The builder's subcortical API: its own functions and the core's meshing they use.
__all__ = ["BLUR_KEEP", "BLUR_VOXELS", "DECIMATION_FRACTIONS", "Structure", "aseg_regions", "aseg_table_path",
           "blur_for", "build_structures", "merge_structures", "mesh_mask", "vertex_normals"]


def aseg_table_path() -> Path:
    """The bundled ``aseg.tsv`` (FreeSurferColorLUT rows of the meshed structures)."""
    return Path(str(resources.files("brainpainter_builder") / "data" / "aseg.tsv"))


def aseg_regions() -> tuple[Region, ...]:
    """Rows of the bundled ``aseg.tsv``."""
    return read_regions_tsv(aseg_table_path())


def build_structures(aseg: NDArray[Any], vox2ras: NDArray[Any], voxel_volume: float,
                     regions: tuple[Region, ...] | None = None, **options: Any) -> list[Structure]:
    """Mesh the aseg structures: :func:`brainpainter.atlas.meshing.build_structures` with
    `regions` defaulting to the bundled ``aseg.tsv`` and `options` passed on."""
    regions = aseg_regions() if regions is None else regions
    return meshing.build_structures(aseg, vox2ras, voxel_volume, regions, **options)

