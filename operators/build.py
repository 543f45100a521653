"""Build the estimate into the scene: armature, camera, or both, into the active take or a new one.

Thin wrappers of ``blender/review/takes.py`` (which builds through ``blender/build.py``): building
again replaces the active take's objects; New Take keeps the others beside it.
"""

from __future__ import annotations

import bpy

from ..core.errors import InputError
from . import common


def _stored(context):
    """(estimate, tracks) from the scene; tracks may be None."""
    from ..blender import scene_data

    est = scene_data.load_estimate(context.scene)
    if est is None:
        raise InputError(common.REASONS["estimate"])
    return est, scene_data.load_tracks(context.scene)


def build(context, *, armature: bool, camera: bool, new: bool = False, est=None) -> dict:
    """Build what is asked from the stored estimate into the active take (or a new one); ``est``: the estimate
    the caller has just stored, so it is not read back."""
    from ..blender import scene_data
    from ..blender.review import takes

    settings = context.scene.monoskel
    est, tracks = _stored(context) if est is None else (est, scene_data.load_tracks(context.scene))
    return takes.build_take(context.scene, est, tracks, new=new, armature=armature, camera=camera,
                            with_motion=settings.build_motion, with_tracks_view=settings.build_tracks_view)


class _BuildBase:
    bl_options = {"REGISTER", "UNDO"}
    needs = ("idle", "estimate")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, cls.needs)


class MONOSKEL_OT_build_armature(_BuildBase, bpy.types.Operator):
    """Build the armature: bone lengths from the estimated proportions at the subject height, keyed motion"""

    bl_idname = "monoskel.build_armature"
    bl_label = "Build Armature"

    def execute(self, context):
        try:
            obj = build(context, armature=True, camera=False)["armature"]
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        self.report({"INFO"}, f"Built armature '{obj.name}' for a {context.scene.monoskel.height_m:.2f} m subject")
        return {"FINISHED"}


class MONOSKEL_OT_build_camera(_BuildBase, bpy.types.Operator):
    """Build the camera: 36 mm sensor, focal length and rotation keyed per frame, the tracks seen through it"""

    bl_idname = "monoskel.build_camera"
    bl_label = "Build Camera"

    def execute(self, context):
        try:
            obj = build(context, armature=False, camera=True)["camera"]
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self.report({"INFO"}, f"Built camera '{obj.name}'")
        return {"FINISHED"}


class MONOSKEL_OT_build_all(_BuildBase, bpy.types.Operator):
    """Build what the Build section asks for (armature, camera, motion, tracks view) into the active take,
    replacing what it held"""

    bl_idname = "monoskel.build_all"
    bl_label = "Build All"

    new: bpy.props.BoolProperty(name="New Take", default=False, options={"SKIP_SAVE"},
                                description="Build into a new take and keep the others beside it")

    def execute(self, context):
        settings = context.scene.monoskel
        if not (settings.build_armature or settings.build_camera):
            return common.fail(self, "Nothing to build: turn on Armature or Camera")
        try:
            built = build(context, armature=settings.build_armature, camera=settings.build_camera, new=self.new)
        except Exception as exc:  # noqa: BLE001 - the build removed what it made; the previous take stays
            return common.fail(self, exc)
        take = settings.takes[settings.take_active]
        self.report({"INFO"}, f"{take.name}: built " + ", ".join(f"'{o.name}'" for o in built.values()))
        return {"FINISHED"}


class MONOSKEL_OT_build_body(_BuildBase, bpy.types.Operator):
    """Build D'Apuzzo's body on the armature: an ellipsoidal metaball per bone, sized from its length and
    adult girths, moving with it (replaces a body it had)"""

    bl_idname = "monoskel.build_body"
    bl_label = "Build Body"
    needs = ("idle", "armature")

    def execute(self, context):
        from ..blender.body.metaballs import replace_body

        settings = context.scene.monoskel
        try:
            objs = replace_body(context.scene, settings.armature, height_m=settings.height_m)
        except Exception as exc:  # noqa: BLE001 - one report line; the old body stays
            return common.fail(self, exc)
        self.report({"INFO"}, f"Built a body of {len(objs)} metaballs on '{settings.armature.name}'")
        return {"FINISHED"}


classes = (MONOSKEL_OT_build_armature, MONOSKEL_OT_build_camera, MONOSKEL_OT_build_all, MONOSKEL_OT_build_body)
