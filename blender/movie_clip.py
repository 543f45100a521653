"""2D joint tracks from the Movie Clip Editor's tracking markers.

The animator tracks the person with Blender's own tracker, one track per
canonical joint, named exactly like the joint (``pelvis``, ``l_knee``, ...).
:func:`create_joint_tracks` makes those 17 named tracks on one frame, laid out
as a stick figure so that each is easy to drag onto its joint;
:func:`tracks_from_clip` turns the tracked markers into core :class:`Tracks`.
Every other track that is not hidden is a background feature (a floor mark, a
wall corner): it becomes a static track (:class:`core.tracks.StaticTracks`),
which pins the camera down (:mod:`core.scene_camera`); hide a track in the
clip editor to leave it out.  :func:`blender_camera_solve` reads Blender's own
camera solve of the clip, to compare with ours.

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
from ..core.lens.prior import META_ASSUMED, META_FOCAL, META_SOURCE
from ..core.skeleton import JOINT_INDEX, JOINTS, N_JOINTS
from ..core.tracks import StaticTracks, Tracks

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
    """Add one track per canonical joint with a marker on clip frame ``frame``, with no weight in
    Blender's own camera solve (a person is no static scene).

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
        track.weight = 0.0      # the person moves: Blender's camera solve must not use these tracks
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


def clip_lens(clip):
    """The lens the clip records (a :class:`core.lens.prior.Lens`), or None: the Movie Clip's camera when the
    user set it (not Blender's defaults), else the movie file's own metadata (:mod:`core.lens`)."""
    from ..core.lens.prior import Lens, lens_from_file

    focal = clip_focal_mm(clip)
    if focal is not None:
        cam = clip.tracking.camera
        return Lens(focal, f"the Movie Clip's camera ({float(cam.focal_length):g} mm on a "
                           f"{float(cam.sensor_width):g} mm sensor)")
    if clip.source != "MOVIE":
        return None
    import bpy

    return lens_from_file(bpy.path.abspath(clip.filepath), clip_size(clip))


def keep_detection(previous, previous_first_frame: int, clip, tracks):
    """``tracks`` read from ``clip``'s markers, with what an earlier *Detect Pose in Clip* on the same clip
    kept beside its 2D joints (``previous``, the scene's tracks shown from scene frame
    ``previous_first_frame``): the detector's 3D joints, placed on the clip frames they were found on,
    and the lens.  Markers hold 2D points only; without this a round of hand corrections would drop them.
    ``tracks`` as they are when ``previous`` is None or came from elsewhere."""
    import os

    import bpy

    if previous is None or not previous.meta.get("detector"):
        return tracks
    names = {clip.name, os.path.basename(bpy.path.abspath(clip.filepath))}
    if previous.source not in names or previous.image_size != tracks.image_size:
        return tracks
    meta = dict(tracks.meta)
    meta.update({k: previous.meta[k] for k in (META_FOCAL, META_SOURCE, META_ASSUMED) if k in previous.meta})
    pts = None
    if previous.landmarks_3d is not None:
        step = max(1, int(previous.meta.get("step", 1) or 1))
        rows = scene_to_clip_frame(clip, previous_first_frame) - 1 + step * np.arange(previous.n_frames)
        ok = (rows >= 0) & (rows < tracks.n_frames)
        pts = np.full((tracks.n_frames, N_JOINTS, 3), np.nan)
        pts[rows[ok]] = previous.landmarks_3d[ok]
        if not np.isfinite(pts).any():
            pts = None
    return tracks.replaced(meta=meta, landmarks_3d=pts)


def background_tracks(clip) -> list:
    """The clip's tracks that are not joints and not hidden: static scene features."""
    return [t for t in _tracks_collection(clip) if t.name.strip().lower() not in JOINT_INDEX and not t.hide]


def marker_pixels(track, marker, width: float, height: float) -> tuple[float, float]:
    """A marker of ``track`` in core pixels (the track's offset added, y down) of a ``width`` x ``height`` clip."""
    ox, oy = track.offset
    u, v = float(marker.co[0]) + ox, float(marker.co[1]) + oy
    return u * width, (1.0 - v) * height


def _marker_points(track, n_frames: int, width: float, height: float):
    """(frames, (k, 2) pixels) of a track's enabled markers inside the clip (core pixels: y down)."""
    frames, pts = [], []
    for marker in track.markers:
        i = int(marker.frame) - 1
        if marker.mute or not 0 <= i < n_frames:
            continue
        frames.append(i)
        pts.append(marker_pixels(track, marker, width, height))
    return np.array(frames, dtype=int), np.array(pts, dtype=float).reshape(-1, 2)


def tracks_from_clip(clip, *, fps: float | None = None, background: bool = True) -> Tracks:
    """The clip's joint-named tracks as core :class:`Tracks` (one frame per clip frame), and with
    ``background`` its other visible tracks as static tracks.

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
    xy = np.full((n_frames, N_JOINTS, 2), np.nan)
    conf = np.zeros((n_frames, N_JOINTS))
    for name, track in found.items():
        frames, pts = _marker_points(track, n_frames, width, height)
        xy[frames, JOINT_INDEX[name]] = pts
        conf[frames, JOINT_INDEX[name]] = 1.0
    if not conf.any():
        raise InputError(f"clip '{clip.name}': the joint tracks have no enabled markers inside the clip")
    static = None
    if background:
        names, sxy, sconf = [], [], []
        for track in background_tracks(clip):
            frames, pts = _marker_points(track, n_frames, width, height)
            if frames.size == 0 or track.name in names:
                continue
            col = np.full((n_frames, 2), np.nan)
            col[frames] = pts
            names.append(track.name)
            sxy.append(col)
            sconf.append(np.isfinite(col[:, 0]).astype(float))
        if names:
            static = StaticTracks(names, np.stack(sxy, axis=1), np.stack(sconf, axis=1))
    return Tracks(xy, conf, rate, (width, height), source=f"clip {clip.name}",
                  meta={"clip": clip.name, "first_frame": int(clip.frame_start)}, static=static)


def blender_camera_solve(clip) -> dict | None:
    """Blender's own camera solve of ``clip`` in the core's conventions, or None when it has none.

    ``{"frames": 0-based clip frames, "rotvec_deg": (k, 3) each camera relative to the first solved one
    (``X_i = R_i X_first``, camera axes x right, y down, z forward), "focal_mm": 36 mm equivalent or None,
    "average_error_px", "tripod"}``.  Blender's camera matrices map its camera axes (y up, looking down -z)
    to the world; ``C = diag(1, -1, -1)`` turns them into ours: ``R_i = C Rb_i^T Rb_first C``.
    """
    rec = clip.tracking.reconstruction
    if not rec.is_valid or len(rec.cameras) < 2:
        return None
    cams = sorted(rec.cameras, key=lambda c: int(c.frame))
    Rb = np.array([[list(row)[:3] for row in list(c.matrix)[:3]] for c in cams], dtype=float)
    flip = np.diag([1.0, -1.0, -1.0])
    R = flip @ np.transpose(Rb, (0, 2, 1)) @ Rb[0] @ flip
    from scipy.spatial.transform import Rotation

    return {"frames": [int(c.frame) - 1 for c in cams],
            "rotvec_deg": np.degrees(Rotation.from_matrix(R).as_rotvec()).tolist(),
            "focal_mm": clip_focal_mm(clip), "average_error_px": float(rec.average_error),
            "tripod": bool(clip.tracking.settings.use_tripod_solver)}
