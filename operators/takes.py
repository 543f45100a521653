"""The take list's buttons: New Take, Make Active, Delete, Compare (thin wrappers of ``blender/review/takes``)."""

from __future__ import annotations

import json

import bpy

from . import common
from .build import build


def _selected(context):
    settings = context.scene.monoskel
    i = settings.take_index
    return i if 0 <= i < len(settings.takes) else -1


class _TakeBase:
    bl_options = {"REGISTER", "UNDO"}
    needs = ("idle", "take")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, cls.needs)


class MONOSKEL_OT_new_take(bpy.types.Operator):
    """Build the estimate into a new take and keep the others beside it"""

    bl_idname = "monoskel.new_take"
    bl_label = "New Take"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "estimate"))

    def execute(self, context):
        settings = context.scene.monoskel
        if not (settings.build_armature or settings.build_camera):
            return common.fail(self, "Nothing to build: turn on Armature or Camera")
        try:
            build(context, armature=settings.build_armature, camera=settings.build_camera, new=True)
        except Exception as exc:  # noqa: BLE001 - one report line; the new take was removed again
            return common.fail(self, exc)
        self.report({"INFO"}, f"New take: {settings.takes[settings.take_active].name}")
        return {"FINISHED"}


class MONOSKEL_OT_take_make_active(_TakeBase, bpy.types.Operator):
    """Make the selected take the active one: Build replaces it, Export uses it, its camera films the scene"""

    bl_idname = "monoskel.take_make_active"
    bl_label = "Make Active"

    def execute(self, context):
        from ..blender.review import takes

        try:
            takes.make_active(context.scene, _selected(context))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self.report({"INFO"}, f"Active take: {context.scene.monoskel.takes[_selected(context)].name}")
        return {"FINISHED"}


class MONOSKEL_OT_take_delete(_TakeBase, bpy.types.Operator):
    """Delete the selected take: its collection, objects, actions, camera and mesh data (Undo brings it back)"""

    bl_idname = "monoskel.take_delete"
    bl_label = "Delete Take"

    def execute(self, context):
        from ..blender.review import takes

        try:
            name = takes.delete_take(context.scene, _selected(context))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        context.scene.monoskel.take_compare = ""
        self.report({"INFO"}, f"Deleted {name}")
        return {"FINISHED"}


class MONOSKEL_OT_take_compare(_TakeBase, bpy.types.Operator):
    """Compare the selected take with the active one: bone lengths and per-frame joint distances"""

    bl_idname = "monoskel.take_compare"
    bl_label = "Compare with Active"
    needs = ("idle", "take", "other_take")

    def execute(self, context):
        from ..blender.review import takes

        settings = context.scene.monoskel
        a, b = takes.active_index(settings), _selected(context)
        try:
            result = takes.compare(context.scene, a, b)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        settings.take_compare = json.dumps(result.summary())   # the panel reads it every redraw: keep it small
        settings.take_compare_names = f"{settings.takes[a].name}\n{settings.takes[b].name}"
        self.report({"INFO"}, f"Joints differ by {result.mean_mm:.0f} mm on average, {result.max_mm:.0f} mm at most"
                    if result.frames.size else "The takes share no posed frame")
        return {"FINISHED"}


classes = (MONOSKEL_OT_new_take, MONOSKEL_OT_take_make_active, MONOSKEL_OT_take_delete, MONOSKEL_OT_take_compare)
