"""Pure-data core of the MonoSkel extension.

Everything here is plain Python + numpy/scipy and must never import ``bpy``:
it runs inside Blender, under ``python -m core`` and under pytest alike.
Modules import each other relatively so that the package works both as the
top-level ``core`` (command line, tests) and as ``<extension>.core`` inside
Blender.
"""

__all__ = ["__version__"]
__version__ = "0.1.0"
