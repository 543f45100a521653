"""Review: jump to a frame the estimate flags (the sidebar's worst-fitting frames); turn a bone the solve
mirrored in depth back over a span of frames."""

from __future__ import annotations

import bpy

from . import common


class MONOSKEL_OT_jump_to_frame(bpy.types.Operator):
    """Go to this frame to see why it fits poorly"""

    bl_idname = "monoskel.jump_to_frame"
    bl_label = "Jump to Frame"
    bl_options = {"INTERNAL"}

    frame: bpy.props.IntProperty(name="Frame")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("estimate",))

    def execute(self, context):
        context.scene.frame_set(int(self.frame))
        return {"FINISHED"}


#: The limb bones an animator can flip (the rig's names), by the joint each ends at.
FLIP_BONES = (("thigh.L", "l_knee"), ("shin.L", "l_ankle"), ("upper_arm.L", "l_elbow"), ("forearm.L", "l_wrist"),
              ("thigh.R", "r_knee"), ("shin.R", "r_ankle"), ("upper_arm.R", "r_elbow"), ("forearm.R", "r_wrist"))


class MONOSKEL_OT_flip_bone_depth(bpy.types.Operator):
    """Turn a limb bone the solve mirrored in depth to its other side over a span of frames (the picture and
    the bone lengths stay as they are); the active take's armature is built again from the corrected motion"""

    bl_idname = "monoskel.flip_bone_depth"
    bl_label = "Flip Bone Depth"
    bl_options = {"REGISTER", "UNDO"}

    bone: bpy.props.EnumProperty(
        name="Bone", default="l_wrist",
        items=[(joint, name, f"The {name} bone (it ends at the {joint} joint)") for name, joint in FLIP_BONES])
    frame_start: bpy.props.IntProperty(name="From Frame",
                                       description="The first scene frame to flip (not given: the current frame)")
    frame_end: bpy.props.IntProperty(name="To Frame",
                                     description="The last scene frame to flip (not given: the first)")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "estimate", "motion"))

    def invoke(self, context, event):
        """The bone selected on the armature in Pose Mode (if a limb's) and the current frame to start from."""
        joint = dict(FLIP_BONES).get(getattr(context.active_pose_bone, "name", None))
        if joint is not None:
            self.bone = joint
        self.frame_start = self.frame_end = context.scene.frame_current
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        from ..blender import scene_data
        from ..core.motion_cleanup.depth_flip import flip_depth
        from . import summary
        from .build import build

        scene = context.scene
        settings = scene.monoskel
        first = int(settings.tracks_first_frame)
        # frames not given (a script, a button without the dialog): the current one
        start = self.frame_start if self.properties.is_property_set("frame_start") else scene.frame_current
        end = self.frame_end if self.properties.is_property_set("frame_end") else start
        start, end = sorted((int(start), int(end)))
        try:
            est = scene_data.load_estimate(scene)
            if est is None:
                return common.fail(self, common.REASONS["estimate"])
            fixed, report = flip_depth(est, self.bone, start - first, end - first)
            scene_data.store_estimate(scene, fixed)
            if settings.armature is not None:
                build(context, armature=True, camera=False, est=fixed)
            summary.set_estimate_summary(settings, fixed)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback; undo restores the rest
            return common.fail(self, exc)
        name = dict((j, n) for n, j in FLIP_BONES)[self.bone]
        plane = f" ({report['in_plane']} in the picture's plane left as they were)" if report["in_plane"] else ""
        target = settings.retarget_target
        again = f"; retarget again to carry it to '{target.name}'" if target is not None else ""
        self.report({"INFO"}, f"{name}: flipped in depth on {report['frames']} frames, {start}-{end}{plane}{again}")
        return {"FINISHED"}


def menu_func_pose(self, context):
    """Pose Mode's right-click menu on the estimate's own armature: Flip Bone Depth for the bone clicked."""
    settings = getattr(context.scene, "monoskel", None)
    if settings is not None and context.object is not None and context.object == settings.armature:
        self.layout.separator()
        self.layout.operator(MONOSKEL_OT_flip_bone_depth.bl_idname, text="Flip Bone Depth (MonoSkel)")


classes = (MONOSKEL_OT_jump_to_frame, MONOSKEL_OT_flip_bone_depth)
