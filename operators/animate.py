"""Animate from Clip: one button from the footage to an animated armature and camera (and the target rig).

The chain is :mod:`blender.animate`: detect the pose, follow the background (unless switched off),
estimate; then the result goes into the scene in one piece (:func:`commit`): the tracks and the estimate,
a new take built with the footage behind its camera, the clip's tracking camera given the solved lens,
the retarget onto the chosen rig, the joint markers and background features on the clip. Interactive runs
are modal: a timer tick does one piece, one progress bar covers all of it, Esc (or Cancel) stops at any
step and leaves the scene as it was. One undo step; a failure anywhere puts everything back.
"""

from __future__ import annotations

import bpy

from ..core.errors import Cancelled, InputError
from . import common
from .detect_pose import poll_clip_and_detector
from .estimate import _set_status
from .movie_clip import find_clip

TIMER_SECONDS = 0.01
#: Frames decoded and detected per timer tick in the interactive run (Esc answers within about 0.5 s).
INTERACTIVE_CHUNK = 8
#: The run the modal operator is running (one at a time), for the sidebar's Cancel button.
_current: list = []


def current():
    return _current[0] if _current else None


def _options(context, clip):
    from ..blender.animate import AnimateOptions

    settings = context.scene.monoskel
    scene_fps = context.scene.render.fps / context.scene.render.fps_base
    return AnimateOptions(mode=settings.detect_mode, step=settings.detect_step,
                          background=bool(settings.animate_background), method=settings.method,
                          focal_mm=None if settings.estimate_focal else float(settings.focal_mm),
                          height_m=float(settings.height_m), fps=clip.fps or scene_fps)


def commit(context, run) -> list:
    """Put a finished run into the scene (all or nothing); returns its notes with the build's and the
    retarget's added."""
    from ..blender.animate import SceneSnapshot
    from ..blender.animate.chain import StageNote
    from ..blender.footage_view import set_tracking_focal, show_footage
    from ..blender.pose_detection.markers import write_joint_markers
    from ..blender.review import takes
    from .estimate import store_result
    from .import_tracks import store_new_tracks
    from .retarget import retarget_active_take

    scene = context.scene
    settings = scene.monoskel
    clip = run._clip()
    target = settings.retarget_target
    if target is not None and (target.type != "ARMATURE" or target == settings.armature):
        target = None
    notes = list(run.notes)
    snapshot = SceneSnapshot(scene, target, clip)
    try:
        numbers = run.detected.frame_numbers
        store_new_tracks(scene, run.tracks, first_frame=int(clip.frame_start) + numbers[0] - 1)
        scene.active_clip = clip
        store_result(scene, run.estimate)
        settings.use_background = run.static_kept
        built = takes.build_take(scene, run.estimate, run.tracks, new=True, armature=True, camera=True,
                                 with_motion=settings.build_motion, with_tracks_view=settings.build_tracks_view)
        take = settings.takes[settings.take_active]
        text = f"build: {take.name}"
        if run.options.step == 1:
            show_footage(built["camera"], clip)
            focal = set_tracking_focal(clip, run.estimate)
            text += f"; the camera shows the footage behind the armature; clip lens {focal:.1f} mm"
        notes.append(StageNote("build", "INFO", text))
        if target is not None:
            line, more = retarget_active_take(scene, target)
            notes.append(StageNote("retarget", "INFO", line))
            notes += [StageNote("retarget", "INFO", n) for n in more]
        write_joint_markers(clip, run.tracks, numbers)
        if run.static_kept:
            run.background.adopt(context)
    except BaseException:
        snapshot.restore()
        run.abort(context)
        raise
    settings.animate_summary = "\n".join(n.text for n in notes)
    return notes


class MONOSKEL_OT_animate_from_clip(bpy.types.Operator):
    """Detect the person in the clip, follow its background for the camera, estimate, build the armature and
    the camera with the footage behind it, and retarget onto the target rig if one is chosen (Esc stops and
    leaves the scene as it was)"""

    bl_idname = "monoskel.animate_from_clip"
    bl_label = "Animate from Clip"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip (empty: the active clip)")

    _run = None
    _timer = None
    _scene_name = ""

    @classmethod
    def poll(cls, context):
        return poll_clip_and_detector(cls, context)

    def _start(self, context, chunk: int):
        from ..blender.animate import AnimateRun

        clip = find_clip(context, self.clip)
        if clip is None:
            raise InputError(f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        return AnimateRun.start(clip, _options(context, clip), chunk=chunk)

    def _finished(self, context, notes) -> set:
        for note in notes:
            if note.level == "WARNING":
                self.report({"WARNING"}, note.text)
        self.report({"INFO"}, "Animate from Clip: " + "; ".join(n.text for n in notes if n.level == "INFO"))
        context.scene.monoskel.animate_message = "Done"
        return {"FINISHED"}

    def execute(self, context):
        from ..blender.animate.chain import run_to_end

        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        try:
            run = run_to_end(self._start(context, chunk=24), context, progress=wm.progress_update)
            notes = commit(context, run)
        except Exception as exc:  # noqa: BLE001 - one report line; the scene is as it was
            context.scene.monoskel.animate_message = "Failed"
            return common.fail(self, exc)
        finally:
            wm.progress_end()
        return self._finished(context, notes)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._run = self._start(context, chunk=INTERACTIVE_CHUNK)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        settings = context.scene.monoskel
        settings.animate_running, settings.animate_progress = True, 0.0
        settings.animate_message = self._run.message
        self._scene_name = context.scene.name
        _current[:] = [self._run]
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(TIMER_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._run.cancel()
        if event.type != "TIMER" and not self._run.cancel_requested:
            return {"PASS_THROUGH"}
        try:
            self._run.step(context)
            if self._run.ready:
                notes = commit(context, self._run)
                self._cleanup(context)
                return self._finished(context, notes)
        except Cancelled:
            self._run.abort(context)
            self._cleanup(context)
            self._scene(context).monoskel.animate_message = "Cancelled"
            self.report({"WARNING"}, "Animate from Clip cancelled; the scene is as it was")
            return {"CANCELLED"}
        except Exception as exc:  # noqa: BLE001 - one report line; the scene is as it was
            self._run.abort(context)
            self._cleanup(context)
            self._scene(context).monoskel.animate_message = "Failed"
            return common.fail(self, exc)
        settings = self._scene(context).monoskel
        settings.animate_progress, settings.animate_message = self._run.fraction, self._run.message
        context.window_manager.progress_update(self._run.fraction)
        _set_status(context, f"MonoSkel: {self._run.message} ({100 * self._run.fraction:.0f}%) - Esc to cancel")
        for area in context.screen.areas if context.screen else ():
            if area.type in {"VIEW_3D", "CLIP_EDITOR"}:
                area.tag_redraw()
        return {"RUNNING_MODAL"} if self._run.stage == "detect" else {"PASS_THROUGH"}

    def cancel(self, context):
        # Blender is tearing the operator down (file load, quit): leave nothing behind.
        if self._run is not None:
            self._run.abort(context)
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
        _current.clear()
        scene = self._scene(context)
        if scene is not None:
            scene.monoskel.animate_running = False
            scene.monoskel.animate_progress = 0.0


class MONOSKEL_OT_animate_cancel(bpy.types.Operator):
    """Stop Animate from Clip; the scene stays as it was"""

    bl_idname = "monoskel.animate_cancel"
    bl_label = "Cancel Animate from Clip"

    @classmethod
    def poll(cls, context):
        if current() is None:
            cls.poll_message_set("Animate from Clip is not running")
            return False
        return True

    def execute(self, context):
        run = current()
        if run is None:
            return common.fail(self, "Animate from Clip is not running")
        run.cancel()
        self.report({"INFO"}, "Cancelling Animate from Clip")
        return {"FINISHED"}


classes = (MONOSKEL_OT_animate_from_clip, MONOSKEL_OT_animate_cancel)
