"""Detect the person in a Movie Clip: decode a chunk, run BlazePose on it, repeat; markers at the end.

:class:`ClipDetection` is stepped by its caller (:meth:`step` does one chunk)
so that the sidebar's modal operator can show progress and take Esc between
chunks, while :func:`detect_clip` runs it to the end for scripts and
``batch.py --video``.  Nothing touches the clip's tracks until
:meth:`ClipDetection.finish`: a run that fails leaves the clip as it was; a
cancelled run keeps (writes) what it detected.
"""

from __future__ import annotations

import os

import bpy

from ...core.errors import InputError
from ...core.pose_detection.detect import DetectionRun
from ...core.pose_detection.video_meta import display_rotation
from ..movie_clip import clip_lens
from .clip_frames import ClipFrames
from .markers import write_joint_markers


def clip_frame_range(clip, start: int | None, end: int | None) -> tuple[int, int]:
    """The clip frames to use (1-based, inclusive), checked against the clip."""
    duration = int(clip.frame_duration)
    if duration < 1:
        raise InputError(f"clip '{clip.name}' has no frames")
    first = 1 if start is None or start <= 0 else int(start)
    last = duration if end is None or end <= 0 else int(end)
    if first > duration:
        raise InputError(f"clip '{clip.name}': start frame {first} is past its last frame ({duration})")
    if last < first:
        raise InputError(f"clip '{clip.name}': end frame {last} is before start frame {first}")
    return first, min(last, duration)


class ClipDetection:
    """One detection run over ``clip``; call :meth:`step` until :attr:`done`, then :meth:`finish`."""

    def __init__(self, clip, *, start: int | None = None, end: int | None = None, step: int = 1,
                 mode: str = "tracking", networks=None, chunk: int = 24, fps: float | None = None):
        first, last = clip_frame_range(clip, start, end)
        self.clip_name = clip.name
        self.run = DetectionRun(fps=fps or clip.fps or None, image_size=tuple(int(v) for v in clip.size),
                                networks=networks, mode=mode, step=step,
                                source=os.path.basename(bpy.path.abspath(clip.filepath)) or clip.name,
                                lens=clip_lens(clip))
        self.frames = ClipFrames(clip, first, last, step=step, chunk=chunk)

    @property
    def done(self) -> bool:
        return self.frames.done

    @property
    def fraction(self) -> float:
        return len(self.run.numbers) / max(1, self.frames.total)

    def step(self) -> None:
        """Decode and detect the next chunk of frames."""
        for number, image in self.frames.next_chunk():
            self.run.add(image, number)

    def finish(self, cancelled: bool = False):
        """Close the decoder; write the joint markers on the clip; return the core Detection.

        Raises :class:`InputError` when no person was found (nothing is written then).
        """
        self.frames.close()
        result = self.run.finish(cancelled=cancelled)
        if result.tracks is not None:
            clip = bpy.data.movieclips.get(self.clip_name)
            if clip is None:
                raise InputError(f"clip '{self.clip_name}' was removed during detection")
            write_joint_markers(clip, result.tracks, result.frame_numbers)
        return result

    def abort(self) -> None:
        """Stop without writing anything (an error, or Blender closing the operator)."""
        self.frames.close()


def detect_clip(clip, *, report=None, progress=None, **options):
    """Run a whole :class:`ClipDetection` (``options`` are its own); ``progress(fraction)`` after every chunk,
    ``report(level, message)`` a line every 10 %."""
    job = ClipDetection(clip, **options)
    last = -1.0
    try:
        while not job.done:
            job.step()
            if progress is not None:
                progress(job.fraction)
            if report is not None and (job.fraction - last >= 0.1 or job.done):
                last = job.fraction
                report("INFO", f"detecting: {len(job.run.numbers)}/{job.frames.total} frames")
    except BaseException:
        job.abort()
        raise
    return job.finish()


def rotation_warning(clip) -> str | None:
    """A warning when the movie asks to be shown turned and this Blender does not turn it (4.2)."""
    if clip.source != "MOVIE" or bpy.app.version >= (4, 5, 0):
        return None
    degrees = display_rotation(bpy.path.abspath(clip.filepath))
    if not degrees:
        return None
    turn = "half a turn" if degrees == 180 else "a quarter turn"
    return (f"'{clip.name}' is flagged to be shown turned {turn} (a phone video), and Blender "
            f"{bpy.app.version_string} ignores the flag: the footage is shown and detected as stored, so "
            f"the camera will come out rolled; Blender 4.5 or newer shows and detects it upright")


def load_clip(path: str):
    """A Movie Clip for the video or first image of a sequence at ``path`` (one clear line when it can't be)."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file")
    try:
        clip = bpy.data.movieclips.load(os.path.abspath(path))
    except RuntimeError as exc:
        raise InputError(f"{path}: Blender cannot open it as a movie or image ({exc})") from None
    if clip.size[0] <= 0 or clip.size[1] <= 0 or clip.frame_duration < 1:
        bpy.data.movieclips.remove(clip)
        raise InputError(f"{path}: Blender cannot read any frame of it (not a video or image?)")
    return clip
