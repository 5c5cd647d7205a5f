"""brainpainter's foci layer: a CSV of MNI152 points (``x,y,z``; optional ``name,value,color,radius``)
drawn as spheres at those points, coloured by value on a scale of its own (a colour bar) or by name
(a key), as Workbench's and BrainNet Viewer's foci.

    brainpainter render --layer foci:peaks.csv --layer-opt foci.cmap=magma --views dorsal -o out/
    brainpainter.Scene(atlas="dk").add("peaks.csv", kind="foci", cmap="magma").render(out="out/")
"""

from __future__ import annotations

from brainpainter.layers.kinds import LayerKind
from brainpainter.layers.readers import Reader

#: The layer kind: its options as ``--layer-opt foci.NAME=VALUE`` or ``Scene.add(..., NAME=VALUE)``.
foci = LayerKind(
    "foci", "MNI152 points from a CSV (x,y,z; optional name,value,color,radius) drawn as spheres",
    options={"cmap": "colour map of the values (default viridis)", "vmin": "value at the first colour",
             "vmax": "value at the last colour", "radius": "sphere radius in mm where the file has none "
             "(default 4)", "color": "colour of foci without a value or colour (default #d62728)",
             "label": "colour-bar label (default: the file's name)"},
    open="bp_layer_foci.layer:open_foci")

#: Its file format, for brainpainter's readers registry (``peaks.foci.csv``).
reader = Reader("foci-csv", "foci", "foci: MNI152 points x,y,z (CSV)", suffixes=(".foci.csv",),
                read="bp_layer_foci.layer:read_foci")
