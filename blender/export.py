"""Export the built result through Blender's own exporters (BVH and FBX), headless or not.

The exporters are operators that read the active/selected objects from the
context; a ``temp_override`` supplies them explicitly, so these functions
work from ``blender -b``, from the PyPI ``bpy`` module and from any editor
without touching the user's selection.
"""

from __future__ import annotations

import os

import bpy

from ..core.errors import InputError
from ..core.io.file_io import check_output_file


def _ensure_addon(module: str) -> None:
    """Enable one of Blender's bundled exporters if the user switched it off."""
    import addon_utils

    loaded_default, loaded_state = addon_utils.check(module)
    if not loaded_state:
        addon_utils.enable(module, default_set=True)


def _override(scene, active, selected):
    view_layer = scene.view_layers[0]
    return bpy.context.temp_override(scene=scene, view_layer=view_layer, active_object=active, object=active,
                                     selected_objects=list(selected), selected_editable_objects=list(selected))


def export_bvh(scene, armature, path) -> str:
    """Write ``armature``'s animation over the scene's frame range as BVH (root translation only)."""
    path = check_output_file(path, None)
    if armature is None or armature.type != 'ARMATURE':
        raise InputError("BVH export needs an armature object")
    _ensure_addon("io_anim_bvh")
    with _override(scene, armature, [armature]):
        result = bpy.ops.export_anim.bvh(filepath=path, check_existing=False, frame_start=scene.frame_start,
                                         frame_end=scene.frame_end, rotate_mode='NATIVE',
                                         root_transform_only=True)
    if 'FINISHED' not in result or not os.path.isfile(path):
        raise RuntimeError(f"{path}: Blender's BVH exporter did not write the file ({result})")
    return path


def export_fbx(scene, objects, path) -> str:
    """Write ``objects`` (armature, camera, ...) with baked animation as FBX."""
    path = check_output_file(path, None)
    objects = [o for o in objects if o is not None]
    if not objects:
        raise InputError("FBX export needs at least one object")
    _ensure_addon("io_scene_fbx")
    # The FBX exporter reads selection flags of the view layer, not only the context list.
    view_layer = scene.view_layers[0]
    previous = {o.name: o.select_get(view_layer=view_layer) for o in scene.objects}
    try:
        for o in scene.objects:
            o.select_set(o in objects, view_layer=view_layer)
        with _override(scene, objects[0], objects):
            result = bpy.ops.export_scene.fbx(
                filepath=path, check_existing=False, use_selection=True,
                object_types={'ARMATURE', 'CAMERA', 'EMPTY'}, add_leaf_bones=False, bake_anim=True,
                bake_anim_use_all_actions=False, bake_anim_use_nla_strips=False, axis_forward='-Z', axis_up='Y')
    finally:
        for o in scene.objects:
            if o.name in previous:
                o.select_set(previous[o.name], view_layer=view_layer)
    if 'FINISHED' not in result or not os.path.isfile(path):
        raise RuntimeError(f"{path}: Blender's FBX exporter did not write the file ({result})")
    return path
