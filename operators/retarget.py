"""Retarget onto the animator's rig: guess or edit the bone map, bake the motion, bone-map presets
(thin wrappers of ``blender/retarget``)."""

from __future__ import annotations

import bpy

from ..core.errors import InputError
from . import common


def _map_from_settings(settings) -> dict[str, str]:
    return {item.role: item.bone for item in settings.retarget_map if item.bone}


def show_map(settings, rig_name: str, bone_map: dict[str, str]) -> None:
    """Put ``bone_map`` into the sidebar's editable rows, one per role."""
    from ..core.retarget.bone_map import ROLES

    settings.retarget_map.clear()
    for role in ROLES:
        item = settings.retarget_map.add()
        item.role = role
        item.bone = bone_map.get(role, "")
    settings.retarget_map_rig = rig_name


def current_map(settings, obj) -> dict[str, str]:
    """The map to use for ``obj``: the sidebar's when it shows this rig, else the stored one, else a guess."""
    from ..blender.retarget.bone_map_store import stored_or_guessed

    if settings.retarget_map_rig == obj.name and len(settings.retarget_map):
        return _map_from_settings(settings)
    return stored_or_guessed(obj)[0]


class _NeedsTarget:
    bl_options = {"REGISTER", "UNDO"}
    needs = ("idle", "target")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, cls.needs)


class MONOSKEL_OT_retarget_guess_map(_NeedsTarget, bpy.types.Operator):
    """Fill the bone map from the target rig: its stored map, or a guess from its bone names and chains"""

    bl_idname = "monoskel.retarget_guess_map"
    bl_label = "Guess Bone Map"

    fresh: bpy.props.BoolProperty(name="Ignore Stored Map", default=False, options={"SKIP_SAVE"},
                                  description="Guess again even when the rig has a stored map")

    def execute(self, context):
        from ..blender.retarget.bone_map_store import stored_or_guessed
        from ..core.retarget import ROLES
        from ..core.retarget.bone_map import REQUIRED

        settings = context.scene.monoskel
        obj = settings.retarget_target
        try:
            bone_map, stored = stored_or_guessed(obj, fresh=self.fresh)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        show_map(settings, obj.name, bone_map)
        missing = [r for r in REQUIRED if r not in bone_map]
        found = sum(1 for r in ROLES if r in bone_map)
        if missing:
            self.report({"WARNING"}, f"Bone map: {found} of {len(ROLES)} parts found; pick "
                        + ", ".join(missing) + " by hand")
        else:
            self.report({"INFO"}, f"Bone map {'stored with the rig' if stored else 'guessed'}: "
                        f"{found} of {len(ROLES)} parts")
        return {"FINISHED"}


class MONOSKEL_OT_retarget(_NeedsTarget, bpy.types.Operator):
    """Bake the active take's motion onto the target rig: bone directions, feet and hands on the source,
    planted feet held, one action of keys"""

    bl_idname = "monoskel.retarget"
    bl_label = "Retarget"
    needs = ("idle", "estimate", "target")

    def execute(self, context):
        settings = context.scene.monoskel
        obj = settings.retarget_target
        wm = context.window_manager
        try:
            wm.progress_begin(0.0, 1.0)
            try:      # the cursor shows how far a frame-by-frame bake (a generated Rigify rig) has come
                line, notes = retarget_active_take(context.scene, obj, progress=wm.progress_update)
            finally:
                wm.progress_end()
        except Exception as exc:  # noqa: BLE001 - the rig keeps its previous action
            return common.fail(self, exc)
        self.report({"INFO"}, line)
        for note in notes:
            self.report({"INFO"}, note)
        return {"FINISHED"}


def retarget_active_take(scene, obj, progress=None) -> tuple[str, list[str]]:
    """Bake the active take's motion onto ``obj`` with the sidebar's map and options; (one line, notes).
    The sidebar shows the map used and the summary; on failure the rig keeps its previous action."""
    from ..blender.retarget.apply import retarget_onto, source_motion
    from ..core.retarget import RetargetSettings

    settings = scene.monoskel
    joints, frames, stance, fps = source_motion(scene)
    bone_map = current_map(settings, obj)
    opts = RetargetSettings(plant_feet=settings.retarget_plant_feet, blend_frames=settings.retarget_blend_frames,
                            smooth_hz=settings.retarget_smooth_hz, ik_hands=settings.retarget_ik_hands)
    result, baked = retarget_onto(obj, joints, frames, bone_map, fps=fps, stance=stance, settings=opts,
                                  max_error_deg=settings.retarget_max_error_deg, progress=progress)
    show_map(settings, obj.name, bone_map)
    miss = float(result.end_error.max()) / result.scale * 100.0 if len(frames) else 0.0
    settings.retarget_summary = (f"{len(result.bones)} bones, {baked['keys']} keys on {len(frames)} frames; "
                                 f"feet and hands within {miss:.1f} cm of the source")
    return f"Retargeted onto '{obj.name}' ({baked['action'].name}): {settings.retarget_summary}", list(result.notes)


class MONOSKEL_OT_retarget_save_preset(_NeedsTarget, bpy.types.Operator):
    """Save the bone map as a preset file, to reuse on other rigs with the same bone names"""

    bl_idname = "monoskel.retarget_save_preset"
    bl_label = "Save Bone Map Preset"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        if not self.filepath:
            self.filepath = f"{context.scene.monoskel.retarget_target.name}_bone_map.json"
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from ..blender.retarget.bone_map_store import write_preset

        settings = context.scene.monoskel
        try:
            if not self.filepath:
                raise InputError("choose a file to save the preset to")
            write_preset(bpy.path.abspath(self.filepath), current_map(settings, settings.retarget_target))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self.report({"INFO"}, f"Saved bone map preset {self.filepath}")
        return {"FINISHED"}


class MONOSKEL_OT_retarget_load_preset(_NeedsTarget, bpy.types.Operator):
    """Load a bone map preset for the target rig (bones it does not have are left empty)"""

    bl_idname = "monoskel.retarget_load_preset"
    bl_label = "Load Bone Map Preset"

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from ..blender.retarget.bone_map_store import read_preset

        settings = context.scene.monoskel
        obj = settings.retarget_target
        try:
            preset = read_preset(bpy.path.abspath(self.filepath))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        bones = obj.data.bones
        usable = {r: b for r, b in preset.items() if b in bones}
        show_map(settings, obj.name, usable)
        dropped = sorted(set(preset) - set(usable))
        self.report({"WARNING"} if dropped else {"INFO"},
                    f"Loaded {len(usable)} parts" + (f"; '{obj.name}' lacks the bones of {', '.join(dropped)}"
                                                     if dropped else ""))
        return {"FINISHED"}


classes = (MONOSKEL_OT_retarget_guess_map, MONOSKEL_OT_retarget, MONOSKEL_OT_retarget_save_preset,
           MONOSKEL_OT_retarget_load_preset)
