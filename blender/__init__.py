"""Blender-side workers: plain functions that turn core results into scene data.

Nothing here registers classes; operators and ``batch.py`` call these
functions and pass a ``report(level, message)`` callback where progress or
warnings matter (the style of Blender's own ``io_anim_bvh``).
"""
