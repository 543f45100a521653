"""The review page's frames of the footage, decoded by Blender as the pose detector's are.

:func:`core.review.footage_sheet.pick_frames` chooses the frames; Blender's sequencer decodes just those
(``blender/pose_detection/clip_frames.py``); the core draws on them.
"""

from __future__ import annotations

from ...core.review.footage_sheet import footage_pictures, pick_frames
from ..pose_detection.clip_frames import ClipFrames


def clip_pictures(clip, est, tracks, first_clip_frame: int = 1, step: int = 1) -> list:
    """:class:`core.review.footage_sheet.Picture` list for ``est`` on ``clip``, whose clip frame
    ``first_clip_frame + step * i`` is the estimate's frame i (``step``: detected on one frame in n)."""
    picks = [(i, why) for i, why in pick_frames(est) if 1 <= first_clip_frame + step * i <= clip.frame_duration]
    if not picks:
        return []
    numbers = [first_clip_frame + step * i for i, _ in picks]
    frames = ClipFrames(clip, min(numbers), max(numbers))
    try:
        rgb = {i: frames.frame(n) for (i, _), n in zip(picks, numbers, strict=True)}
    finally:
        frames.close()
    if tracks.image_size != (float(frames.width), float(frames.height)):
        sx, sy = frames.width / tracks.image_size[0], frames.height / tracks.image_size[1]
        if abs(sx - sy) > 0.01 * sx:
            return []           # another picture than the tracks': nothing can be drawn on it truthfully
        tracks = tracks.replaced(xy=tracks.xy * sx, image_size=(float(frames.width), float(frames.height)),
                                 static=None)
    return footage_pictures(est, tracks, rgb, picks)
