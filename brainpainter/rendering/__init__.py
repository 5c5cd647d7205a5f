"""From values to pixels: views and cameras, the scene and its geometry, the painter, parallel and
cluster runs.
"""
