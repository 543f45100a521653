"""2D joint tracks from the Movie Clip Editor's tracking markers.

The animator tracks the person with Blender's own tracker, one track per
canonical joint, named exactly like the joint (``pelvis``, ``l_knee``, ...).
:func:`create_joint_tracks` makes those 17 named tracks on one frame, laid out
as a stick figure so that each is easy to drag onto its joint;
:func:`tracks_from_clip` turns the tracked markers into core :class:`Tracks`.

Conventions that differ between Blender and the core, handled here only:

* ``marker.co`` is normalised to the frame, origin bottom-left, y up; core
  pixels have their origin top-left, y down.
* Marker frames are the clip's own frame numbers (1 = first image), while the
  scene shows clip frame 1 at ``clip.frame_start``.
* A muted (disabled) marker, or no marker on a frame, means "missing".  Blender
  shows the last marker until the next one, but only exact markers are data.
* The tracking camera's focal length is in mm of its own sensor width; the
  core wants the 36 mm-film equivalent of :mod:`core.camera`.
"""

from __future__ import annotations

import numpy as np

from ..core.camera import mm_per_pixel
from ..core.errors import InputError
from ..core.skeleton import JOINT_INDEX, JOINTS, N_JOINTS
from ..core.tracks import Tracks

#: Where each new joint track starts, normalised (x right, y up), as a figure facing the camera
#: (its left on the image's right) filling the middle of the frame.
FIGURE_LAYOUT: dict[str, tuple[float, float]] = {
    "head": (0.50, 0.86), "neck": (0.50, 0.78), "thorax": (0.50, 0.72), "spine": (0.50, 0.62),
    "pelvis": (0.50, 0.52),
    "l_hip": (0.54, 0.51), "l_knee": (0.55, 0.34), "l_ankle": (0.55, 0.16),
    "r_hip": (0.46, 0.51), "r_knee": (0.45, 0.34), "r_ankle": (0.45, 0.16),
    "l_shoulder": (0.57, 0.74), "l_elbow": (0.60, 0.62), "l_wrist": (0.62, 0.51),
    "r_shoulder": (0.43, 0.74), "r_elbow": (0.40, 0.62), "r_wrist": (0.38, 0.51),
}

#: Blender's tracking-camera defaults; a clip still holding them has no focal length set.
DEFAULT_CAMERA = (24.0, 35.0)


def scene_to_clip_frame(clip, scene_frame: int) -> int:
    """The clip's own frame number shown at ``scene_frame`` (clip frame 1 at ``clip.frame_start``)."""
    return int(scene_frame) - int(clip.frame_start) + 1


def _tracks_collection(clip):
    """The tracks of the active tracking object (the camera's tracks unless the user chose another)."""
    active = clip.tracking.objects.active
    return active.tracks if active is not None else clip.tracking.tracks


def joint_tracks(clip) -> dict[str, object]:
    """Canonical joint name -> the clip track named after it (names match case-insensitively)."""
    found = {}
    for track in _tracks_collection(clip):
        name = track.name.strip().lower()
        if name in JOINT_INDEX and name not in found:
            found[name] = track
    return found


def create_joint_tracks(clip, frame: int) -> list[str]:
    """Add one track per canonical joint with a marker on clip frame ``frame``.

    Joints that already have a track are left alone (their markers may hold hours of
    work).  Returns the names of the tracks created, selected so the animator can
    start tracking them at once.
    """
    if not 1 <= frame <= max(1, clip.frame_duration):
        raise InputError(f"clip '{clip.name}': frame {frame} is outside the clip (1-{clip.frame_duration})")
    existing = joint_tracks(clip)
    collection = _tracks_collection(clip)
    for track in collection:
        track.select = False
    created = []
    for name in JOINTS:
        if name in existing:
            continue
        track = collection.new(name=name, frame=frame)
        marker = track.markers.find_frame(frame, exact=True)
        if marker is None:
            marker = track.markers.insert_frame(frame)
        marker.co = FIGURE_LAYOUT[name]
        track.select = True
        created.append(name)
    return created


def clip_size(clip) -> tuple[float, float]:
    """Image size in square pixels (anamorphic clips are widened by their pixel aspect)."""
    width, height = (float(v) for v in clip.size)
    if width <= 0 or height <= 0:
        raise InputError(f"clip '{clip.name}': its frames cannot be read (size {width:g}x{height:g})")
    return width * float(clip.tracking.camera.pixel_aspect or 1.0), height


def clip_focal_mm(clip) -> float | None:
    """The tracking camera's focal length as a 36 mm-film equivalent, or None when it was never set."""
    cam = clip.tracking.camera
    focal, sensor = float(cam.focal_length), float(cam.sensor_width)
    if (round(focal, 4), round(sensor, 4)) == DEFAULT_CAMERA or focal <= 0 or sensor <= 0:
        return None
    width, height = clip_size(clip)
    focal_px = focal / sensor * width
    return focal_px * mm_per_pixel((width, height))


def tracks_from_clip(clip, *, fps: float | None = None) -> Tracks:
    """The clip's joint-named tracks as core :class:`Tracks` (one frame per clip frame).

    ``fps`` is used when the clip has none (image sequences report 0).
    """
    found = joint_tracks(clip)
    if not found:
        raise InputError(f"clip '{clip.name}': no tracks named after the canonical joints "
                         f"({', '.join(JOINTS[:3])}, ...); add them with 'Add Joint Tracks' first")
    n_frames = int(clip.frame_duration)
    if n_frames <= 0:
        raise InputError(f"clip '{clip.name}': the clip has no frames")
    clip_fps = float(clip.fps or 0.0)
    rate = clip_fps if clip_fps > 0 else (float(fps) if fps else 0.0)
    if rate <= 0:
        raise InputError(f"clip '{clip.name}': no frame rate (set the scene's frame rate)")
    width, height = clip_size(clip)
    aspect_x = width / float(clip.size[0])
    xy = np.full((n_frames, N_JOINTS, 2), np.nan)
    conf = np.zeros((n_frames, N_JOINTS))
    for name, track in found.items():
        j = JOINT_INDEX[name]
        ox, oy = track.offset
        for marker in track.markers:
            i = int(marker.frame) - 1
            if marker.mute or not 0 <= i < n_frames:
                continue
            u, v = float(marker.co[0]) + ox, float(marker.co[1]) + oy
            xy[i, j] = (u * float(clip.size[0]) * aspect_x, (1.0 - v) * height)
            conf[i, j] = 1.0
    if not conf.any():
        raise InputError(f"clip '{clip.name}': the joint tracks have no enabled markers inside the clip")
    return Tracks(xy, conf, rate, (width, height), source=f"clip {clip.name}",
                  meta={"clip": clip.name, "first_frame": int(clip.frame_start)})
