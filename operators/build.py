"""Build the estimate into the scene: armature, camera, or both (thin wrappers of ``blender/build.py``)."""

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


def build_armature(context, est, replace: bool = True):
    """Build the armature; with ``replace`` the previous one goes and the new one takes its names."""
    from ..blender import build

    settings = context.scene.monoskel
    obj = build.build_armature(context.scene, est, height_m=settings.height_m, with_motion=settings.build_motion,
                               first_frame=settings.tracks_first_frame)
    if replace:
        build.replace_built(settings.armature, obj)    # building again replaces the previous armature
        settings.armature = obj
    return obj


def build_camera(context, est, tracks, replace: bool = True):
    """Build the camera; with ``replace`` the previous one (and its tracks view) goes."""
    from ..blender import build

    settings = context.scene.monoskel
    obj = build.build_camera(context.scene, est, tracks, height_m=settings.height_m,
                             first_frame=settings.tracks_first_frame,
                             with_tracks_view=settings.build_tracks_view)
    if replace:
        build.replace_built(settings.camera, obj)
        settings.camera = obj
        _prune(context, est)
    return obj


def _prune(context, est) -> None:
    """Drop the timeline markers an earlier estimate's build left (spells and problems that are gone)."""
    from ..blender import review

    review.prune_markers(context.scene, review.expected_markers(est, context.scene.monoskel.tracks_first_frame))


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
            est, _ = _stored(context)
            obj = build_armature(context, est)
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
            est, tracks = _stored(context)
            obj = build_camera(context, est, tracks)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self.report({"INFO"}, f"Built camera '{obj.name}' (focal {est.focal_mm:.1f} mm)")
        return {"FINISHED"}


class MONOSKEL_OT_build_all(_BuildBase, bpy.types.Operator):
    """Build what the Build section asks for (armature, camera, motion, tracks view) in one step"""

    bl_idname = "monoskel.build_all"
    bl_label = "Build All"

    def execute(self, context):
        settings = context.scene.monoskel
        if not (settings.build_armature or settings.build_camera):
            return common.fail(self, "Nothing to build: turn on Armature or Camera")
        from ..blender.build import remove_built, replace_built

        built = {}
        try:
            est, tracks = _stored(context)
            if settings.build_armature:
                built["armature"] = build_armature(context, est, replace=False)
            if settings.build_camera:
                built["camera"] = build_camera(context, est, tracks, replace=False)
        except Exception as exc:  # noqa: BLE001
            # Each builder cleaned up after itself; remove what the earlier step built too.  The previous
            # build is untouched: it is replaced only once every step has succeeded.
            for obj in built.values():
                remove_built(obj)
            return common.fail(self, exc)
        for attr, obj in built.items():
            replace_built(getattr(settings, attr), obj)
            setattr(settings, attr, obj)
        if "camera" in built:
            _prune(context, est)
        built = list(built.values())
        self.report({"INFO"}, "Built " + ", ".join(f"'{o.name}'" for o in built))
        return {"FINISHED"}


classes = (MONOSKEL_OT_build_armature, MONOSKEL_OT_build_camera, MONOSKEL_OT_build_all)
