"""Import a BVH (or a built-in motion) as test data: tracks filmed by a virtual camera, plus the truth."""

from __future__ import annotations

import bpy

from . import common, summary
from .import_tracks import describe_tracks, store_new_tracks


class MONOSKEL_OT_import_test_data(bpy.types.Operator):
    """Film a known motion with a virtual camera: 2D tracks to estimate from, and the truth to compare with"""

    bl_idname = "monoskel.import_test_data"
    bl_label = "Make Test Data"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "test_source"))

    def execute(self, context):
        from ..blender import scene_data, test_data

        scene = context.scene
        settings = scene.monoskel
        source = settings.test_bvh_path if settings.test_source == "FILE" else settings.test_source
        if settings.test_source == "FILE" and not source:
            return common.fail(self, "Choose a BVH file first")
        kinds = [item.identifier for item in settings.bl_rna.properties["test_kinds"].enum_items
                 if item.identifier in settings.test_kinds]
        armature = None
        try:
            tracks, truth, armature = test_data.import_bvh_test_data(
                context, source, kinds=kinds, noise_px=settings.test_noise_px, dropout=settings.test_dropout,
                seed=settings.test_seed, max_frames=settings.test_max_frames or None,
                height_m=settings.height_m,
            )
            store_new_tracks(scene, tracks, first_frame=1)
            scene_data.store_truth(scene, truth)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            if armature is not None:
                test_data.remove_armature(armature)
            return common.fail(self, exc)
        summary.set_truth_summary(settings, truth)
        settings.truth_armature = armature
        self.report({"INFO"}, f"Test data from {source}: {describe_tracks(tracks)}; "
                              f"truth armature '{armature.name}'")
        return {"FINISHED"}


classes = (MONOSKEL_OT_import_test_data,)
