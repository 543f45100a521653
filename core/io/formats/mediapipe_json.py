"""MediaPipe Pose landmarks in a JSON file.

Accepted shapes (what the usual export scripts write):

* the top level is a list of frames, or ``{"frames": [...]}`` with optional
  ``"fps"`` and ``"image_size": [w, h]`` (or ``"width"``/``"height"``);
* a frame is a list of 33 landmarks, or an object whose ``"landmarks"`` /
  ``"pose_landmarks"`` holds them (also ``{"landmark": [...]}`` as written by
  protobuf's MessageToDict, and a list of poses, as from the Tasks API, where
  the pose with the highest mean visibility is taken); ``null``, ``[]`` or a
  frame without landmarks means no detection;
* a landmark is ``{"x", "y"}`` with optional ``"z"``, ``"visibility"``,
  ``"presence"``.

If every frame object has an integer ``"frame"``, those numbers order the
frames and gaps become empty frames; otherwise the list order is the frame
order.
"""

from __future__ import annotations

import numpy as np

from ...errors import InputError
from ...tracks import Tracks
from ..file_io import read_json_file
from ._canonical import check_fps, check_image_size, choose_fps, choose_image_size
from ._io import finite_float, frame_positions
from .mediapipe import N_LANDMARKS, landmarks_to_tracks

LABEL = "MediaPipe JSON"
LANDMARK_KEYS = ("landmarks", "pose_landmarks", "poseLandmarks")


def _landmark_list(frame):
    """The frame's landmark list (or list of poses), None when the frame has no detection."""
    if frame is None:
        return None
    if isinstance(frame, dict):
        for key in LANDMARK_KEYS:
            if key in frame:
                frame = frame[key]
                break
        else:
            return None
        if isinstance(frame, dict) and "landmark" in frame:
            frame = frame["landmark"]
    return frame


def _pose(landmarks, source: str, where: str) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(landmarks, list) or len(landmarks) != N_LANDMARKS:
        got = len(landmarks) if isinstance(landmarks, list) else type(landmarks).__name__
        raise InputError(f"{source}: {where}: expected {N_LANDMARKS} landmarks, got {got}")
    xy = np.empty((N_LANDMARKS, 2))
    vis = np.ones(N_LANDMARKS)
    for i, lm in enumerate(landmarks):
        if not isinstance(lm, dict) or "x" not in lm or "y" not in lm:
            raise InputError(f"{source}: {where}, landmark {i}: expected an object with \"x\" and \"y\"")
        for k, key in enumerate(("x", "y")):
            value = finite_float(lm[key])
            if value is None:
                raise InputError(f"{source}: {where}, landmark {i}: {key}={lm[key]!r} is not a finite number")
            xy[i, k] = value
        if "visibility" in lm:
            value = finite_float(lm["visibility"])
            if value is None or value < 0:
                raise InputError(f"{source}: {where}, landmark {i}: visibility={lm['visibility']!r} must be a "
                                 "number >= 0")
            vis[i] = value
    return xy, vis


def _frame_pose(frame, source: str, where: str):
    landmarks = _landmark_list(frame)
    if landmarks is None or landmarks == []:
        return None
    if isinstance(landmarks, list) and landmarks and all(isinstance(p, list) for p in landmarks):
        poses = [_pose(p, source, f"{where}, pose {k}") for k, p in enumerate(landmarks) if p]
        return max(poses, key=lambda p: p[1].mean()) if poses else None
    return _pose(landmarks, source, where)


def read_mediapipe_json(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    doc = read_json_file(source)
    file_fps = file_size = None
    if isinstance(doc, dict) and isinstance(doc.get("frames"), list):
        if doc.get("fps") is not None:
            file_fps = check_fps(doc["fps"], source)
        if doc.get("image_size") is not None:
            file_size = check_image_size(doc["image_size"], source)
        elif doc.get("width") is not None or doc.get("height") is not None:
            file_size = check_image_size((doc.get("width"), doc.get("height")), source)
        frames = doc["frames"]
    elif isinstance(doc, list):
        frames = doc
    else:
        raise InputError(f"{source}: not MediaPipe landmarks (expected a list of frames or {{\"frames\": [...]}})")
    if not frames:
        raise InputError(f"{source}: no frames")
    numbers = [f.get("frame") if isinstance(f, dict) else None for f in frames]
    if all(isinstance(n, int) and not isinstance(n, bool) for n in numbers):
        if len(set(numbers)) != len(numbers):
            raise InputError(f"{source}: a frame number is listed twice")
        rows, first, n = frame_positions(numbers, source)
    else:
        rows, first, n = list(range(len(frames))), 0, len(frames)
    fps = choose_fps(fps, file_fps, LABEL, source)
    image_size = choose_image_size(image_size, file_size, LABEL, source)
    xy = np.full((n, N_LANDMARKS, 2), np.nan)
    vis = np.zeros((n, N_LANDMARKS))
    for k, (r, frame) in enumerate(zip(rows, frames, strict=True)):
        pose = _frame_pose(frame, source, f"frame {k}")
        if pose is not None:
            xy[r], vis[r] = pose
    meta = {"format": "mediapipe_json", "first_frame": first}
    return landmarks_to_tracks(xy, vis, fps=fps, image_size=image_size, source=source, meta=meta)
