"""Re-read the scene's stored data into the sidebar summary, and fix it up after a file is opened."""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from ..blender import estimate_job
from . import common, summary


class MONOSKEL_OT_refresh(bpy.types.Operator):
    """Re-read the tracks, estimate and truth stored in this scene (e.g. after running batch.py)"""

    bl_idname = "monoskel.refresh"
    bl_label = "Refresh from Scene Data"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle",))

    def execute(self, context):
        try:
            summary.refresh_from_scene(context.scene)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        s = context.scene.monoskel
        self.report({"INFO"}, f"Tracks: {'yes' if s.has_tracks else 'no'}, estimate: "
                              f"{'yes' if s.has_estimate else 'no'}, truth: {'yes' if s.has_truth else 'no'}")
        return {"FINISHED"}


@persistent
def on_load_post(*_args):
    """No estimate survives a file load; files written by batch.py get their summary filled in."""
    estimate_job.set_current(None)
    for scene in bpy.data.scenes:
        settings = getattr(scene, "monoskel", None)
        if settings is None:
            continue
        settings.estimate_running = False
        settings.estimate_progress = 0.0
        if not settings.has_tracks and any(k.startswith("monoskel_") for k in scene.keys()):
            try:
                summary.refresh_from_scene(scene)
            except Exception:  # noqa: BLE001 - a bad stored document must not break opening the file
                pass


classes = (MONOSKEL_OT_refresh,)
