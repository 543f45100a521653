"""Review: jump to a frame the estimate flags (the sidebar's worst-fitting frames); turn a bone the solve
mirrored in depth back over a span of frames; hold a foot the solve let slide still over a span of frames."""

from __future__ import annotations

import bpy

from ..blender.build_armature import BONES
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


def correct_estimate(op, context, correct):
    """Apply an animator's correction ``correct(est) -> (corrected estimate, report)`` to the stored estimate:
    store it, build the active take's armature again from it and update the sidebar's summary. Returns the
    report, or the operator's cancelled set after one report line (never a traceback; undo restores the rest)."""
    from ..blender import scene_data
    from . import summary
    from .build import build

    scene = context.scene
    settings = scene.monoskel
    try:
        est = scene_data.load_estimate(scene)
        if est is None:
            return common.fail(op, common.REASONS["estimate"])
        fixed, report = correct(est)
        scene_data.store_estimate(scene, fixed)
        if settings.armature is not None:
            build(context, armature=True, camera=False, est=fixed)
        summary.set_estimate_summary(settings, fixed)
    except Exception as exc:  # noqa: BLE001 - one report line, never a traceback; undo restores the rest
        return common.fail(op, exc)
    return report


def retarget_again(settings) -> str:
    """The report's reminder that a retargeted rig does not follow a correction by itself."""
    target = settings.retarget_target
    return f"; retarget again to carry it to '{target.name}'" if target is not None else ""


#: The limb bones an animator can flip (upper and lower leg and arm), by the joint each ends at, the left side's
#: first: taken from the rig's one naming table, so that a bone's name is written in one place.
FLIP_BONES = tuple(sorted(((name, tail) for name, _, tail, _ in BONES
                           if tail[2:] in ("knee", "ankle", "elbow", "wrist")), key=lambda bone: bone[1][0]))


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
        from ..core.motion_cleanup.depth_flip import flip_depth

        scene = context.scene
        first = int(scene.monoskel.tracks_first_frame)
        # frames not given (a script, a button without the dialog): the current one
        start = self.frame_start if self.properties.is_property_set("frame_start") else scene.frame_current
        end = self.frame_end if self.properties.is_property_set("frame_end") else start
        start, end = sorted((int(start), int(end)))
        report = correct_estimate(self, context, lambda est: flip_depth(est, self.bone, start - first, end - first))
        if not isinstance(report, dict):
            return report
        name = dict((j, n) for n, j in FLIP_BONES)[self.bone]
        plane = f" ({report['in_plane']} in the picture's plane left as they were)" if report["in_plane"] else ""
        self.report({"INFO"}, f"{name}: flipped in depth on {report['frames']} frames, {start}-{end}{plane}"
                              f"{retarget_again(scene.monoskel)}")
        return {"FINISHED"}


#: The rig's leg bones, by the foot they carry (Plant Foot's side from the bone clicked).
LEG_SIDES = {name: tail[0] for name, _, tail, _ in BONES if tail[2:] in ("hip", "knee", "ankle")}


class MONOSKEL_OT_plant_foot(bpy.types.Operator):
    """Hold a foot the solve let slide still in the world over a span of frames (the leg bends to reach it,
    eased in and out); the active take's armature is built again from the corrected motion"""

    bl_idname = "monoskel.plant_foot"
    bl_label = "Plant Foot"
    bl_options = {"REGISTER", "UNDO"}

    foot: bpy.props.EnumProperty(name="Foot", default="l",
                                 items=[("l", "Left", "The left foot"), ("r", "Right", "The right foot")])
    frame_start: bpy.props.IntProperty(
        name="From Frame",
        description="The first scene frame the foot stands (not given: where it stands around the current frame)")
    frame_end: bpy.props.IntProperty(name="To Frame",
                                     description="The last scene frame the foot stands (not given: as From Frame)")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "estimate", "motion"))

    def _span(self, context, est) -> tuple[int, int]:
        """Scene frames: the ones given, else the frames the foot stands around the current one (else that one)."""
        from ..core.errors import InputError
        from ..core.motion_cleanup.foot_plant import stance_span

        scene = context.scene
        first = int(scene.monoskel.tracks_first_frame)
        given = [self.properties.is_property_set(k) for k in ("frame_start", "frame_end")]
        if given[0]:
            start = int(self.frame_start)
            return tuple(sorted((start, int(self.frame_end) if given[1] else start)))
        if est is None:
            return scene.frame_current, scene.frame_current
        try:
            a, b = stance_span(est, self.foot, scene.frame_current - first)
        except InputError:
            return scene.frame_current, scene.frame_current
        return a + first, b + first

    def invoke(self, context, event):
        """The side of the leg bone selected in Pose Mode, and the span that foot stands around the current frame."""
        from ..blender import scene_data

        foot = LEG_SIDES.get(getattr(context.active_pose_bone, "name", None))
        if foot is not None:
            self.foot = foot
        try:
            self.frame_start, self.frame_end = self._span(context, scene_data.load_estimate(context.scene))
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        from ..core.motion_cleanup.foot_plant import REACH_WARN_M, SIDE_NAMES, plant_foot, reach_warning

        first = int(context.scene.monoskel.tracks_first_frame)
        report = correct_estimate(self, context, lambda est: plant_foot(
            est, self.foot, *(frame - first for frame in self._span(context, est))))
        if not isinstance(report, dict):
            return report
        start, end = report["first"] + first, report["last"] + first
        body = (f"; the body slid back up to {100 * report['body_slide_m']:.0f} cm to reach it"
                if report["body_slide_m"] > 0 else "")
        said = (f"{SIDE_NAMES[self.foot].capitalize()} foot held still on frames {start}-{end} (it had strayed up "
                f"to {100 * report['slide_m']:.0f} cm{body}){retarget_again(context.scene.monoskel)}")
        if report["unreached_m"] > REACH_WARN_M:
            self.report({"WARNING"}, f"{said}; {reach_warning(report)}")
        else:
            self.report({"INFO"}, said)
        return {"FINISHED"}


def menu_func_pose(self, context):
    """Pose Mode's right-click menu on the estimate's own armature: Flip Bone Depth for the bone clicked, and
    Plant Foot for the leg it is on."""
    settings = getattr(context.scene, "monoskel", None)
    if settings is not None and context.object is not None and context.object == settings.armature:
        self.layout.separator()
        self.layout.operator(MONOSKEL_OT_flip_bone_depth.bl_idname, text="Flip Bone Depth (MonoSkel)")
        self.layout.operator(MONOSKEL_OT_plant_foot.bl_idname, text="Plant Foot (MonoSkel)")


classes = (MONOSKEL_OT_jump_to_frame, MONOSKEL_OT_flip_bone_depth, MONOSKEL_OT_plant_foot)
