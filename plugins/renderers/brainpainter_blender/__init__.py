"""Blender renderer plugin for brainpainter (``bpy``, Workbench and Cycles).

Registered under the ``brainpainter.renderers`` entry point ``blender``.
Importing this package does not import ``bpy``; creating a
:class:`BlenderRenderer` does.
"""

from brainpainter_blender.renderer import BlenderRenderer

__all__ = ["BlenderRenderer"]
