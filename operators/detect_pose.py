"""Detect Pose in Clip: BlazePose on the active Movie Clip, joint markers on the clip, tracks on the scene.

Thin: the work is :mod:`blender.pose_detection` (decoding, markers) and
:mod:`core.pose_detection` (the detector).  Interactive runs are modal: a
timer tick decodes and detects one chunk of frames, the status bar and the
sidebar show progress, Esc stops and keeps what was detected.  In the
background (scripts, ``batch.py``) it runs to the end in one call.
"""

from __future__ import annotations

import bpy

from ..core.errors import InputError
from . import common
from .estimate import _set_status
from .import_tracks import describe_tracks, store_new_tracks
from .movie_clip import find_clip

TIMER_SECONDS = 0.01
#: frames decoded and detected per timer tick in the interactive run (about 0.5 s: Esc answers that fast)
INTERACTIVE_CHUNK = 8
_AVAILABLE: list = []  # (ok, why), computed once per process (a file check and imports)


def detector_available() -> tuple[bool, str]:
    """Whether the detector's optional part is installed, and if not, why (cached for the process: an
    install into Blender's Python takes a restart anyway)."""
    if not _AVAILABLE:
        from ..core.pose_detection.runtime import available

        _AVAILABLE[:] = [available()]
    return _AVAILABLE[0]


def _scene_fps(scene) -> float:
    return scene.render.fps / scene.render.fps_base


def _tracks_onto_scene(scene, clip, result) -> str:
    """The detected tracks become the scene's, shown from the clip frame they start at.

    (The markers on the clip hold the same points: *Tracks from Clip* reads them back after hand
    corrections.)"""
    from ..blender.pose_detection.clip_detect import rotation_warning

    tracks = result.tracks
    store_new_tracks(scene, tracks, first_frame=int(clip.frame_start) + result.frame_numbers[0] - 1)
    turned = rotation_warning(clip)
    if turned:
        result.notes.append(turned)
    if scene.active_clip is None:
        scene.active_clip = clip
    n = len(result.frame_numbers)
    speed = n / max(result.seconds, 1e-9)
    head = "Detection stopped: kept" if result.cancelled else "Detected"
    notes = "".join(f"; {note}" for note in result.notes)
    lens = tracks.meta.get("lens_source")
    if lens:
        notes += f"; lens {tracks.meta['lens_focal_mm']:.1f} mm (36 mm film) from {lens}"
    return (f"{head} {n} frames of '{clip.name}' (person in {100 * result.found_share:.0f} %, "
            f"{speed:.1f} frames/s): {describe_tracks(tracks)}{notes}")



def poll_clip_and_detector(cls, context) -> bool:
    """Poll of every operator that detects the pose on a clip: nothing else running, a clip at hand and the
    detector installed; otherwise the reason goes to the button's tooltip."""
    if not common.poll_requirements(cls, context, ("idle",)):
        return False
    if find_clip(context) is None:
        cls.poll_message_set(common.REASONS["clip"])
        return False
    ok, why = detector_available()
    if not ok:
        cls.poll_message_set(why)
        return False
    return True

class MONOSKEL_OT_detect_pose(bpy.types.Operator):
    """Find the person's joints on every frame of the clip with BlazePose (offline), as joint-named markers on
    the clip and as the scene's tracks (Esc stops and keeps what was found)"""

    bl_idname = "monoskel.detect_pose"
    bl_label = "Detect Pose in Clip"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip (empty: the active clip)")
    start: bpy.props.IntProperty(name="Start", default=0, min=0, description="First clip frame (0: the first)")
    end: bpy.props.IntProperty(name="End", default=0, min=0, description="Last clip frame (0: the last)")

    _job = None
    _timer = None
    _scene_name = ""
    _clip_name = ""

    @classmethod
    def poll(cls, context):
        return poll_clip_and_detector(cls, context)

    def _clip_and_options(self, context) -> tuple:
        """The clip to detect in and the :class:`ClipDetection` options from this operator and the sidebar."""
        clip = find_clip(context, self.clip)
        if clip is None:
            raise InputError(f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        settings = context.scene.monoskel
        return clip, {"start": self.start or None, "end": self.end or None, "step": settings.detect_step,
                      "mode": settings.detect_mode, "fps": clip.fps or _scene_fps(context.scene)}

    def execute(self, context):
        from ..blender.pose_detection.clip_detect import detect_clip

        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        try:
            clip, options = self._clip_and_options(context)
            result = detect_clip(clip, progress=wm.progress_update, **options)
            message = _tracks_onto_scene(context.scene, clip, result)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        finally:
            wm.progress_end()
        self.report({"WARNING"} if result.notes else {"INFO"}, message)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        from ..blender.pose_detection.clip_detect import ClipDetection

        try:
            clip, options = self._clip_and_options(context)
            self._job = ClipDetection(clip, chunk=INTERACTIVE_CHUNK, **options)
        except Exception as exc:  # noqa: BLE001
            return common.fail(self, exc)
        self._clip_name = clip.name
        self._scene_name = context.scene.name
        settings = context.scene.monoskel
        settings.detect_running, settings.detect_progress, settings.detect_message = True, 0.0, "Starting"
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(TIMER_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        _set_status(context, "MonoSkel: detecting the pose (Esc to stop and keep what was found)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            return self._finish(context, cancelled=True)
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            self._job.step()
        except Exception as exc:  # noqa: BLE001
            self._job.abort()
            self._cleanup(context)
            self._scene(context).monoskel.detect_message = "Failed"
            return common.fail(self, exc)
        done = len(self._job.run.numbers)
        text = f"Detecting: frame {done}/{self._job.frames.total}"
        settings = self._scene(context).monoskel
        settings.detect_progress, settings.detect_message = self._job.fraction, text
        context.window_manager.progress_update(self._job.fraction)
        _set_status(context, f"MonoSkel: {text} - Esc to stop and keep what was found")
        for area in context.screen.areas if context.screen else ():
            if area.type in {"VIEW_3D", "CLIP_EDITOR"}:
                area.tag_redraw()
        if not self._job.done:
            return {"RUNNING_MODAL"}
        return self._finish(context, cancelled=False)

    def cancel(self, context):
        # Blender is tearing the operator down (file load, quit): write nothing.
        if self._job is not None:
            self._job.abort()
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
            scene.monoskel.detect_running = False
            scene.monoskel.detect_progress = 0.0

    def _finish(self, context, cancelled: bool):
        self._cleanup(context)
        scene = self._scene(context)
        try:
            result = self._job.finish(cancelled=cancelled)
            if result.tracks is None:
                scene.monoskel.detect_message = "Stopped before any frame"
                self.report({"WARNING"}, "Detection stopped before any frame; nothing changed")
                return {"CANCELLED"}
            message = _tracks_onto_scene(scene, bpy.data.movieclips[self._clip_name], result)
        except Exception as exc:  # noqa: BLE001
            scene.monoskel.detect_message = "Failed"
            return common.fail(self, exc)
        scene.monoskel.detect_message = "Stopped" if cancelled else "Done"
        self.report({"WARNING"} if cancelled or result.notes else {"INFO"}, message)
        return {"FINISHED"}


classes = (MONOSKEL_OT_detect_pose,)
