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


def _poll_pose(cls, context) -> bool:
    return common.poll_requirements(cls, context, ("idle", "pose"))


def _repose(operator, context) -> set:
    from ..blender import single_image

    try:
        pose = single_image.repose(context.scene, context.scene.monoskel)
    except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
        return common.fail(operator, exc)
    if pose is None:
        return common.fail(operator, "The pose's input is gone from the scene: pose the frame again")
    return {"FINISHED"}


class MONOSKEL_OT_pose_flip_segment(bpy.types.Operator):
    """Flip this segment's depth: its far end comes nearer the camera than its near end, or the reverse"""

    bl_idname = "monoskel.pose_flip_segment"
    bl_label = "Flip Segment Depth"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    index: bpy.props.IntProperty(name="Segment", min=0, max=15)

    @classmethod
    def poll(cls, context):
        return _poll_pose(cls, context)

    def execute(self, context):
        settings = context.scene.monoskel
        settings.si_signs[self.index] = not settings.si_signs[self.index]
        return _repose(self, context)


class MONOSKEL_OT_pose_scale(bpy.types.Operator):
    """Stretch the single-image pose in depth (Taylor's scale; it stops at the smallest that fits)"""

    bl_idname = "monoskel.pose_scale"
    bl_label = "Pose Scale"
    bl_options = {"REGISTER", "UNDO"}

    scale: bpy.props.FloatProperty(name="Scale (px/m)", min=0.0, soft_max=5000.0,
                                   description="Pixels per metre: larger stretches the pose in depth")

    @classmethod
    def poll(cls, context):
        return _poll_pose(cls, context)

    def invoke(self, context, event):
        self.scale = context.scene.monoskel.si_scale
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return context.window_manager.invoke_props_popup(self, event)   # a slider that re-poses as it moves

    def execute(self, context):
        settings = context.scene.monoskel
        settings.si_scale = max(float(self.scale), float(settings.si_scale_min))
        return _repose(self, context)


classes = (MONOSKEL_OT_pose_from_image, MONOSKEL_OT_pose_flip_segment, MONOSKEL_OT_pose_scale)
