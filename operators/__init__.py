"""Operators: thin Blender wrappers around ``core`` (one ordered class list)."""

import bpy

classes = ()
register, unregister = bpy.utils.register_classes_factory(classes)
