"""Pose from one image: the current frame's joints -> an armature posed at this frame (Taylor 2000)."""

from __future__ import annotations

import bpy

from . import common


class MONOSKEL_OT_pose_from_image(bpy.types.Operator):
    """Pose an armature at the current frame from this frame's 2D joints alone, with a camera that sees it on them"""

    bl_idname = "monoskel.pose_from_image"
    bl_label = "Pose from Image"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("tracks", "idle"))

    def execute(self, context):
        from ..blender import single_image

        try:
            pose, arm, _ = single_image.pose_scene(context.scene, context.scene.monoskel)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        notes = []
        if pose.ambiguous:
            notes.append(f"check {', '.join(single_image.SEGMENT_NAMES[k] for k in pose.ambiguous)} "
                         "(either depth fits)")
        missing = single_image.missing_joints(pose)
        if missing:
            notes.append(f"not seen, hanging down: {', '.join(missing)}")
        self.report({"INFO"}, f"Posed '{arm.name}' at frame {context.scene.frame_current}"
                              + (f"; {'; '.join(notes)}" if notes else ""))
        return {"FINISHED"}


classes = (MONOSKEL_OT_pose_from_image,)
