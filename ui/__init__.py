"""Sidebar panels of the 3D Viewport (one ordered class list)."""

import bpy

from . import panels

classes = panels.classes
register, unregister = bpy.utils.register_classes_factory(classes)
