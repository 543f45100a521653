"""Estimate proportions, camera and motion from the scene's tracks.

With a window the operator is modal: the core runs in a background thread
(:mod:`blender.estimate_job`), a window-manager timer polls its progress into the status
bar and the sidebar, and ESC or the sidebar's Cancel button stops it.  Without a
window (``blender -b``, the ``bpy`` module, tests) timers never fire, so
``execute`` runs the same computation synchronously.
"""

from __future__ import annotations

import bpy

from ..blender import estimate_job
from ..core.errors import InputError
from . import common, summary

TIMER_SECONDS = 0.1


def _inputs(context):
    """Everything the worker needs, read on the main thread: (tracks, method, focal or None, height,
    Blender's camera solve of the tracks' clip or None, whether to use the background tracks, the
    further views and their cameras)."""
    from ..blender import movie_clip, scene_data

    settings = context.scene.monoskel
    tracks = scene_data.load_tracks(context.scene)
    if tracks is None:
        raise InputError(common.REASONS["tracks"])
    focal = None if settings.estimate_focal else float(settings.focal_mm)
    solve = None
    if tracks.source.startswith("clip "):
        clip = bpy.data.movieclips.get(tracks.source[len("clip "):])
        solve = movie_clip.blender_camera_solve(clip) if clip is not None else None
    views, cameras = scene_data.load_views(context.scene)
    return (tracks, settings.method, focal, float(settings.height_m), solve, bool(settings.use_background),
            views, cameras)


def _make_run(tracks, method, focal, height, solve=None, background=True, views=(), cameras=None):
    """The estimate as a function of (progress, should_cancel): one view's method, or with further
    ``views`` the multi-view estimate (the method and the background tracks do not apply there)."""
    from ..core.camera import mm_per_pixel
    from ..core.estimate import estimate
    from ..core.multiview import estimate_multiview

    def run(progress=None, should_cancel=None):
        if views:
            focal_px = [None if focal is None else focal / mm_per_pixel(tracks.image_size)] + [None] * len(views)
            return estimate_multiview([tracks, *views], cameras=cameras, height_m=height, focal_px=focal_px,
                                      progress=progress, should_cancel=should_cancel)
        est = estimate(tracks, method, focal_mm=focal, height_m=height,
                       progress=progress, should_cancel=should_cancel, background=background)
        if solve is not None:
            est.diagnostics["blender_solve"] = compare_with_solve(est, solve)
        return est

    return run


def compare_with_solve(est, solve) -> dict | None:
    """How far the estimate's camera is from Blender's solve (core.scene_camera.compare)."""
    import numpy as np

    from ..core.scene_camera.compare import compare_cameras

    return compare_cameras(np.array([f.rotvec_deg for f in est.frames]), np.array([f.focal_mm for f in est.frames]),
                           solve)


def store_result(scene, est) -> str:
    """Put a finished estimate on the scene (main thread only) and describe it in one line."""
    from ..blender import scene_data

    scene_data.store_estimate(scene, est)
    summary.set_estimate_summary(scene.monoskel, est)
    diag = est.diagnostics or {}
    if diag.get("cameras"):
        errors = ", ".join(f"{e:.1f}" for e in diag.get("view_reprojection_px", []))
        return (f"Estimated from {len(diag['cameras'])} views: {len(est.frames)} frames, reprojection "
                f"{errors} px per view")
    from ..core.lens.prior import describe

    spells = diag.get("spells") or []
    lens = describe(diag.get("lens"))
    return (f"Estimated ({est.method}): focal {est.focal_mm:.1f} mm, {len(est.frames)} frames, "
            f"{len(spells)} camera spell(s)" + (f"; {lens}" if lens else ""))


def _set_status(context, text: str | None) -> None:
    workspace = getattr(context, "workspace", None)
    if workspace is not None and hasattr(workspace, "status_text_set"):
        workspace.status_text_set(text)
    area = getattr(context, "area", None)
    if area is not None:
        area.header_text_set(text)


class MONOSKEL_OT_estimate(bpy.types.Operator):
    """Estimate the skeleton proportions, the camera and the motion from the tracks (ESC cancels)"""

    bl_idname = "monoskel.estimate"
    bl_label = "Estimate"
    bl_options = {"REGISTER", "UNDO"}

    _job = None
    _timer = None
    _scene_name = ""

    @classmethod
    def poll(cls, context):
        if estimate_job.current() is not None:
            cls.poll_message_set(common.REASONS["idle"])
            return False
        return common.poll_requirements(cls, context, ("tracks", "idle"))

    def execute(self, context):
        try:
            run = _make_run(*_inputs(context))
            wm = context.window_manager
            wm.progress_begin(0.0, 1.0)
            try:
                est = run(progress=lambda fraction, message="": wm.progress_update(float(fraction)))
            finally:
                wm.progress_end()
            message = store_result(context.scene, est)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback (Cancelled included)
            return common.fail(self, exc)
        self.report({"INFO"}, message)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            run = _make_run(*_inputs(context))
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        settings = context.scene.monoskel
        settings.estimate_running = True
        settings.estimate_progress = 0.0
        settings.estimate_message = "Starting"
        self._scene_name = context.scene.name
        self._job = estimate_job.EstimateJob(run)
        estimate_job.set_current(self._job)
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(TIMER_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        self._job.start()
        _set_status(context, "MonoSkel: estimating (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._job.cancel()
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":  # (any timer: polling a little more often is harmless)
            return {"PASS_THROUGH"}
        state = self._job.snapshot()
        scene = self._scene(context)
        if scene is not None:
            settings = scene.monoskel
            settings.estimate_progress = state.fraction
            settings.estimate_message = "Cancelling" if self._job.cancel_requested and not state.done \
                else state.message
        context.window_manager.progress_update(state.fraction)
        _set_status(context, f"MonoSkel: {state.message} ({100 * state.fraction:.0f}%) - Esc to cancel")
        for area in context.screen.areas if context.screen else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()
        if not state.done:
            return {"PASS_THROUGH"}
        return self._finish(context, state)

    def cancel(self, context):
        # Blender is tearing the operator down (file load, quit): stop the worker, drop its result.
        if self._job is not None:
            self._job.cancel()
        self._cleanup(context)

    def _scene(self, context):
        return bpy.data.scenes.get(self._scene_name) or context.scene

    def _cleanup(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        _set_status(context, None)
        scene = self._scene(context)
        if scene is not None:
            scene.monoskel.estimate_running = False
            scene.monoskel.estimate_progress = 0.0
        estimate_job.set_current(None)

    def _finish(self, context, state):
        self._cleanup(context)
        scene = self._scene(context)
        if state.cancelled:
            scene.monoskel.estimate_message = "Cancelled"
            self.report({"WARNING"}, "Estimate cancelled; the scene keeps its earlier result")
            return {"CANCELLED"}
        if state.error is not None:
            scene.monoskel.estimate_message = "Failed"
            return common.fail(self, state.error)
        try:
            message = store_result(scene, state.result)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        scene.monoskel.estimate_message = "Done"
        self.report({"INFO"}, message)
        return {"FINISHED"}


class MONOSKEL_OT_estimate_cancel(bpy.types.Operator):
    """Stop the running estimate; the scene keeps its earlier result"""

    bl_idname = "monoskel.estimate_cancel"
    bl_label = "Cancel Estimate"

    @classmethod
    def poll(cls, context):
        if estimate_job.current() is None:
            cls.poll_message_set("No estimate is running")
            return False
        return True

    def execute(self, context):
        job = estimate_job.current()
        if job is None:
            return common.fail(self, "No estimate is running")
        job.cancel()
        self.report({"INFO"}, "Cancelling the estimate")
        return {"FINISHED"}


classes = (MONOSKEL_OT_estimate, MONOSKEL_OT_estimate_cancel)
