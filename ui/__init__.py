"""Sidebar panels of the 3D Viewport (one ordered class list) and the residual-lines overlay."""

import bpy

from . import panels

classes = panels.classes
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    from ..blender.review import overlay

    _register_classes()
    overlay.register()


def unregister():
    from ..blender.review import overlay

    overlay.unregister()
    _unregister_classes()
