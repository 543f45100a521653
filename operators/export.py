"""Export the built armature (BVH) or armature + camera (FBX) through Blender's own exporters."""

from __future__ import annotations

import bpy
from bpy_extras.io_utils import ExportHelper

from . import common


class _ExportBase(ExportHelper):
    #: Name of the scene setting that remembers the last path.
    path_setting = ""

    def invoke(self, context, event):
        stored = getattr(context.scene.monoskel, self.path_setting)
        if stored:
            self.filepath = bpy.path.abspath(stored)
        return ExportHelper.invoke(self, context, event)

    def _remember(self, context):
        setattr(context.scene.monoskel, self.path_setting, self.filepath)


class MONOSKEL_OT_export_bvh(_ExportBase, bpy.types.Operator):
    """Export the built armature's motion as BVH (Blender's BVH exporter)"""

    bl_idname = "monoskel.export_bvh"
    bl_label = "Export BVH"
    bl_options = {"REGISTER"}

    filename_ext = ".bvh"
    filter_glob: bpy.props.StringProperty(default="*.bvh", options={"HIDDEN"})
    path_setting = "bvh_path"

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "armature"))

    def execute(self, context):
        from ..blender.export import export_bvh

        scene = context.scene
        try:
            path = export_bvh(scene, scene.monoskel.armature, bpy.path.abspath(self.filepath))
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        self._remember(context)
        self.report({"INFO"}, f"Exported BVH to {path}")
        return {"FINISHED"}


class MONOSKEL_OT_export_fbx(_ExportBase, bpy.types.Operator):
    """Export the built armature and camera, with their animation, as FBX (Blender's FBX exporter)"""

    bl_idname = "monoskel.export_fbx"
    bl_label = "Export FBX"
    bl_options = {"REGISTER"}

    filename_ext = ".fbx"
    filter_glob: bpy.props.StringProperty(default="*.fbx", options={"HIDDEN"})
    path_setting = "fbx_path"

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "built"))

    def execute(self, context):
        from ..blender.export import export_fbx

        scene = context.scene
        settings = scene.monoskel
        objects = [o for o in (settings.armature, settings.camera) if o is not None]
        try:
            path = export_fbx(scene, objects, bpy.path.abspath(self.filepath))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self._remember(context)
        self.report({"INFO"}, f"Exported FBX ({', '.join(o.name for o in objects)}) to {path}")
        return {"FINISHED"}


classes = (MONOSKEL_OT_export_bvh, MONOSKEL_OT_export_fbx)
