"""Blender renderer plugin for brainpainter (``bpy``: its ``gpu`` module by default, Cycles for high quality).

Registered under the ``brainpainter.renderers`` entry point ``blender``.
Importing this package does not import ``bpy``; creating a
:class:`BlenderRenderer` does.
"""

from brainpainter_blender.renderer import BlenderRenderer

__all__ = ["BlenderRenderer"]
