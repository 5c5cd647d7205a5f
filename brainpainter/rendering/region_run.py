"""A run whose first layer is a region table (or tracts or a connectome alone, over an empty one).

:func:`prepare_region_run` reads the table (and the tract values, the connectome, the blobs and the
plugin layers given with it), checks every option and builds the :class:`~brainpainter.rendering.run.Run`
whose first layer colours each region (:class:`~brainpainter.layers.regions.RegionValues`).
"""

from __future__ import annotations

from typing import Any

from brainpainter.atlas.model import Atlas
from brainpainter.connectome.series import check_images
from brainpainter.layers.kinds import open_layers
from brainpainter.layers.over import over_layers
from brainpainter.layers.regions import RegionValues
from brainpainter.rendering.alone import alone_source, default_views, drawn_alone, empty_table
from brainpainter.rendering.blob_layers import drawn_blobs, load_blobs
from brainpainter.rendering.checked_run import Run
from brainpainter.rendering.composition import cortex_for, line_layers, region_run_layers
from brainpainter.rendering.options import Options
from brainpainter.rendering.painter import flat_aspect, shown_aspect
from brainpainter.rendering.settings import with_aspect
from brainpainter.rendering.tract_run import read_run_table, run_tract_values
from brainpainter.rendering.views import parse_views, with_clip


def prepare_region_run(data: Any, atlas_obj: Atlas | None, options: Options) -> Run:
    """Read the region table (or what is drawn alone) and check the options of its run
    (:func:`brainpainter.rendering.run.prepare_run`)."""
    views = options.scene.views
    if views is not None:  # a given option's errors before a big input file is read
        view_list = parse_views(views if isinstance(views, str) else list(views))
    tract_values, bundles_only = run_tract_values(data, options)
    blobs = load_blobs(options)
    drawn = open_layers(options.scene.layer, options.scene.layer_opt)
    alone = drawn_alone(data, options, tract_values, bundles_only, blobs, drawn)  # None: a region table
    if alone is None:
        table = read_run_table(data, atlas_obj, options, tract_values)
    else:
        images = (tract_values.images or ("1",)) if alone == "tracts" and tract_values is not None else ()
        table = empty_table(atlas_obj, alone_source(alone, data, options), images,
                            "table" if alone == "tracts" else "connectome")
    connectome = options.connectome.load(table.atlas, options.scene.template, options.scene.surface,
                                         atlas_given=alone != "connectome" or atlas_obj is not None)
    if alone == "connectome" and connectome is not None and connectome.series is not None:
        table = empty_table(table.atlas, options.connectome.connectome, connectome.series.names)
    check_images(connectome, len(table.images), f"table {table.source!r} has")
    if views is None:
        view_list = parse_views(default_views(table.atlas, alone))
    view_list = with_clip(view_list, options.scene.clips)
    own = (table.atlas.name, table.atlas.template_labels)
    contours, settings = line_layers(options, "a region render", own)
    cortical = {r.key for r in table.atlas.cortical()}
    settings = cortex_for(settings, cortex_values=bool(cortical.intersection(table.regions)),
                          tracts=bool(options.scene.tracts),
                          connectome=connectome is not None or bool(blobs) or bool(drawn))
    if not options.size_given and table.atlas.image_aspect:  # a brain of another shape: frame the views
        settings = with_aspect(settings, shown_aspect(table.atlas, options.scene.template, view_list))
    elif not options.size_given and (aspect := flat_aspect(view_list)):  # flat maps: wider than a brain
        settings = with_aspect(settings, aspect)
    layers = region_run_layers(options, table, tract_values, alone == "tracts", connectome, blobs,
                               None if alone == "tracts" else alone)
    layers += tuple(layer.layer() for layer in drawn)
    drawn = (*drawn_blobs(blobs, layers), *drawn)
    regions = RegionValues(table, next((la.scale for la in layers if la.kind == "regions"), layers[0].scale))
    return Run(table, layers[0].scale, view_list, settings, options, regions,
               over_layers(layers, table.images, tract_values, connectome, drawn), layers, tract_values,
               contours, connectome, blobs, drawn)
