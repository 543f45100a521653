"""What every operator needs: the reasons a button is disabled, and one-line failure reports.

The same :func:`missing_requirement` feeds ``poll_message_set`` (the tooltip of a
disabled button) and the sidebar's "why" labels (``ui/state.py``), so the two can
never disagree.
"""

from __future__ import annotations

from ..core.errors import InputError

#: Requirement name -> one-line reason shown when it is not met.
REASONS = {
    "tracks": "Import tracks first",
    "idle": "An estimate is running; wait or cancel it",
    "estimate": "Run Estimate first",
    "motion": "The estimate has no 3D motion; run a method that solves it",
    "armature": "Build the armature first",
    "built": "Build the armature or the camera first",
    "clip": "Open a movie clip in the Movie Clip Editor first",
    "test_source": "Choose a BVH file first",
    "pose": "Pose a frame from the image first",
    "take": "Build a take first, then select it in the list",
    "other_take": "Select a take other than the active one",
    "target": "Choose your character's armature as the target rig",
    "views": "Add a further view's tracks first",
    "detecting": "A pose detection is running; wait or press Esc",
    "animating": "Animate from Clip is running; wait or press Esc",
}


def missing_requirement(settings, needs) -> str | None:
    """The reason for the first unmet requirement in ``needs`` (None: all met).

    ``settings`` is ``scene.monoskel``; only its summary fields are read, so this is
    cheap enough for ``poll`` and ``draw``.
    """
    for need in needs:
        if need == "idle" and settings.estimate_running:
            return REASONS[need]
        if need == "idle" and getattr(settings, "detect_running", False):
            return REASONS["detecting"]
        if need == "idle" and getattr(settings, "animate_running", False):
            return REASONS["animating"]
        if need == "tracks" and not settings.has_tracks:
            return REASONS[need]
        if need == "views" and settings.views_count == 0:
            return REASONS[need]
        if need == "estimate" and not settings.has_estimate:
            return REASONS[need]
        if need == "motion" and settings.has_estimate and not settings.est_has_motion:
            return REASONS[need]
        if need == "armature" and settings.armature is None:
            return REASONS[need]
        if need == "test_source" and settings.test_source == "FILE" and not settings.test_bvh_path:
            return REASONS[need]
        if need == "built" and settings.armature is None and settings.camera is None:
            return REASONS[need]
        if need == "pose" and (not settings.si_has_pose or settings.si_armature is None):
            return REASONS[need]
        if need == "target":
            target = settings.retarget_target
            if target is None or target.type != "ARMATURE" or target == settings.armature:
                return REASONS[need]
        n_takes = len(settings.takes)
        if need == "take" and not 0 <= settings.take_index < n_takes:
            return REASONS[need]
        if need == "other_take" and (not 0 <= settings.take_active < n_takes
                                     or settings.take_active == settings.take_index):
            return REASONS[need]
    return None


def poll_requirements(cls, context, needs) -> bool:
    """``poll`` body: True when every requirement is met, else False with the reason set."""
    scene = getattr(context, "scene", None)
    if scene is None or not hasattr(scene, "monoskel"):
        cls.poll_message_set("No scene")
        return False
    reason = missing_requirement(scene.monoskel, needs)
    if reason:
        cls.poll_message_set(reason)
        return False
    return True


def one_line(exc: BaseException) -> str:
    """A single-line message for a report; InputError messages are already one line."""
    text = str(exc).strip() or type(exc).__name__
    text = " ".join(text.split())
    if not isinstance(exc, InputError):
        text = f"{type(exc).__name__}: {text}"
    return text


def fail(operator, exc_or_message) -> set:
    """Report one ERROR line and cancel (the shape of every failure path)."""
    message = exc_or_message if isinstance(exc_or_message, str) else one_line(exc_or_message)
    operator.report({"ERROR"}, message)
    return {"CANCELLED"}


def set_scene_timing(scene, fps: float, n_frames: int, first_frame: int | None = None) -> None:
    """Make the scene play the clip at its own rate: fps (with fps_base for 29.97 etc.) and range.

    Frame ``first_frame`` (default: the scene's start) shows tracks frame 0.
    """
    whole = max(1, round(fps))
    scene.render.fps = whole
    scene.render.fps_base = whole / fps
    start = scene.frame_start if first_frame is None else int(first_frame)
    scene.frame_start = start
    scene.frame_end = start + max(1, int(n_frames)) - 1
