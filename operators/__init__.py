"""Operators: thin Blender wrappers around ``core`` and ``blender/`` (one ordered class list)."""

import bpy

from . import (
    animate,
    build,
    detect_pose,
    estimate,
    export,
    import_tracks,
    movie_clip,
    refresh,
    retarget,
    review,
    single_image,
    takes,
    test_data,
    trim_tracks,
    views,
)

classes = (
    *import_tracks.classes,
    *trim_tracks.classes,
    *views.classes,
    *movie_clip.classes,
    *detect_pose.classes,
    *animate.classes,
    *test_data.classes,
    *estimate.classes,
    *build.classes,
    *takes.classes,
    *retarget.classes,
    *single_image.classes,
    *review.classes,
    *export.classes,
    *refresh.classes,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.TOPBAR_MT_file_import.append(import_tracks.menu_func_import)
    bpy.types.VIEW3D_MT_pose_context_menu.append(review.menu_func_pose)
    if refresh.on_load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(refresh.on_load_post)


def unregister():
    if refresh.on_load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(refresh.on_load_post)
    bpy.types.VIEW3D_MT_pose_context_menu.remove(review.menu_func_pose)
    bpy.types.TOPBAR_MT_file_import.remove(import_tracks.menu_func_import)
    job = estimate.estimate_job.current()
    if job is not None:
        job.cancel()
        estimate.estimate_job.set_current(None)
    _unregister_classes()
