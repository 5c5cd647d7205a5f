"""Connectomes: a connectivity matrix with its nodes, read and thresholded.

``model`` the :class:`~brainpainter.connectome.model.Connectome` (nodes with
positions, values, categories and labels; the edge weights). The scene model
(:mod:`brainpainter.rendering`) turns a connectome into node spheres and edge
cylinders. Everything here is numpy (scipy to read ``.mat``, nibabel for CIFTI
``pconn``).
"""
