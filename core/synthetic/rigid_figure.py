"""A rigid, left/right-symmetric canonical figure that follows a real motion.

Why: motion capture skeletons are not rigid once mapped to 17 joints (marker
noise, mapping choices, virtual points), and they are rarely symmetric.  The
synthetic experiment needs *exact* ground-truth proportions, so we keep only
the *directions* of the captured segments and rebuild the figure from the
root down with fixed lengths: ``child = parent + L * unit(direction)``.

Steps of :func:`motion_from_bvh_file`: read and map the BVH (``core.io.bvh``,
``core.io.bvh_mapping``); drop an inserted pose-less first frame (a T-pose
frame that jumps away from the rest of the clip, as in CMU ``01_01``);
rotate the file's up axis to +Y; resample to ``fps`` by linear
interpolation *before* rebuilding (so lengths stay exact); average each
class's length over frames and over left/right; scale so the standing
height (:func:`core.skeleton.standing_height`) is ``height_m``; rebuild;
put the lowest ankle of the clip at ankle height above the floor y = 0 and
frame 0's pelvis over the origin.
"""

from __future__ import annotations

import os

import numpy as np

from ..errors import InputError
from ..io.bvh import read_bvh, up_axis
from ..io.bvh_mapping import build_mapping, canonical_positions
from ..skeleton import (
    ANKLE_HEIGHT_FRACTION,
    FEET,
    JOINT_INDEX,
    SEGMENT_CLASS,
    SEGMENTS,
    class_lengths_from_segments,
    segment_lengths,
    standing_height,
)
from .motion_clip import Motion

#: A foot is "low" if its ankle is within this fraction of the figure's
#: stature above the clip's lowest ankle height.
CONTACT_HEIGHT_FRACTION = 0.035
#: ... and "slow" if the ankle moves less than this many statures per second.
CONTACT_SPEED_FRACTION = 0.25


def foot_contacts(joints: np.ndarray, fps: float) -> np.ndarray:
    """Planted feet, (F, 2) bool (columns left, right): the ankle is low *and* slow.

    ``joints`` is (F, 17, 3) metres, Y up.  Thresholds scale with the
    figure's stature (from its first frame's segment lengths) so the rule
    works for any height.  "Low" is measured from the lowest ankle over the
    clip (robust 1st percentile), so it does not depend on where the floor is.
    """
    joints = np.asarray(joints, dtype=float)
    n = joints.shape[0]
    contacts = np.zeros((n, 2), dtype=bool)
    if n == 0:
        return contacts
    stature = float(standing_height(class_lengths_from_segments(segment_lengths(joints[0]))))
    ankles = joints[:, [FEET["l"], FEET["r"]], :]                      # (F, 2, 3)
    floor = np.percentile(ankles[:, :, 1], 1.0)
    low = ankles[:, :, 1] - floor < CONTACT_HEIGHT_FRACTION * stature
    if n == 1:
        return low
    velocity = np.gradient(ankles, axis=0) * float(fps)               # central differences
    slow = np.linalg.norm(velocity, axis=-1) < CONTACT_SPEED_FRACTION * stature
    return low & slow


def motion_from_bvh_file(path, height_m: float = 1.75, fps: float | None = None) -> Motion:
    """A rigid canonical :class:`Motion` (metres, Y up, floor y = 0) following a BVH clip."""
    path = os.fspath(path)
    if not np.isfinite(height_m) or height_m <= 0:
        raise InputError(f"height must be a positive number of metres, got {height_m!r}")
    if fps is not None and (not np.isfinite(fps) or fps <= 0):
        raise InputError(f"fps must be positive, got {fps!r}")
    bvh = read_bvh(path)
    mapping = build_mapping(bvh)
    points = canonical_positions(bvh, mapping)                           # (F, 17, 3) file units
    dropped = 0
    if _first_frame_is_inserted(points):
        points = points[1:]
        dropped = 1
    axis, sign = up_axis(bvh, frame=dropped)
    points = points @ _to_y_up(axis, sign).T
    source_fps = nice_fps(bvh.fps)
    lengths_from = points
    if fps is not None and abs(fps - source_fps) > 1e-9 * source_fps:
        points = resample(points, source_fps, fps)
        out_fps = float(fps)
    else:
        out_fps = float(source_fps)
    if points.shape[0] < 1:
        raise InputError(f"{path}: no frames left after resampling")
    joints, class_lengths = rigid_rebuild(points, height_m, where=path, lengths_from=lengths_from)
    contacts = foot_contacts(joints, out_fps)
    name = os.path.splitext(os.path.basename(path))[0]
    meta = {"source": path, "bvh_joints": mapping.names(bvh), "mapping_notes": mapping.notes,
            "dropped_first_frames": dropped, "up_axis": "xyz"[axis] if sign > 0 else "-" + "xyz"[axis],
            "source_fps": float(source_fps), "height_m": float(height_m)}
    return Motion(name, out_fps, joints, class_lengths, contacts, meta)


def rigid_rebuild(points: np.ndarray, height_m: float, where: str = "motion",
                  lengths_from: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rigid symmetric figure (F, 17, 3) metres and its class lengths (10,) from Y-up points (F, 17, 3).

    ``points`` may be in any unit; the figure is scaled to ``height_m``.  The
    class lengths are the mean over the frames of ``lengths_from`` (default
    ``points``; the clip at its own rate, so resampling does not change the
    proportions).
    """
    points = np.asarray(points, dtype=float)
    seg = segment_lengths(points if lengths_from is None else lengths_from)   # (F, 16)
    class_lengths = class_lengths_from_segments(seg.mean(axis=0))
    if np.any(class_lengths <= 0) or not np.all(np.isfinite(class_lengths)):
        raise InputError(f"{where}: a mapped segment has no length; cannot build a figure")
    scale = height_m / float(standing_height(class_lengths))
    class_lengths = class_lengths * scale
    joints = np.empty_like(points)
    joints[:, 0] = points[:, 0] * scale
    for s, (parent, child) in enumerate(SEGMENTS):
        direction = points[:, child] - points[:, parent]
        joints[:, child] = joints[:, parent] + class_lengths[SEGMENT_CLASS[s]] * _unit_directions(direction)
    ankles = joints[:, [FEET["l"], FEET["r"]], 1]
    joints[..., 1] += ANKLE_HEIGHT_FRACTION * height_m - ankles.min()
    joints[..., 0] -= joints[0, JOINT_INDEX["pelvis"], 0]
    joints[..., 2] -= joints[0, JOINT_INDEX["pelvis"], 2]
    return joints, class_lengths


def nice_fps(fps: float) -> float:
    """``Frame Time: 0.0333333`` means 30 fps: snap to an integer rate within 0.05 %."""
    rounded = round(fps)
    return float(rounded) if rounded > 0 and abs(fps - rounded) < 5e-4 * fps else float(fps)


def resample(points: np.ndarray, source_fps: float, fps: float) -> np.ndarray:
    """Linear interpolation of (F, ...) samples from ``source_fps`` to ``fps`` over the same duration."""
    n = points.shape[0]
    duration = (n - 1) / source_fps
    times = np.arange(int(np.floor(duration * fps + 1e-9)) + 1) / fps
    position = times * source_fps
    lo = np.minimum(np.floor(position).astype(int), n - 1)
    hi = np.minimum(lo + 1, n - 1)
    w = (position - lo).reshape((-1,) + (1,) * (points.ndim - 1))
    return points[lo] * (1 - w) + points[hi] * w


def _unit_directions(direction: np.ndarray) -> np.ndarray:
    """Unit vectors (F, 3); a degenerate frame borrows the nearest valid frame's direction."""
    norm = np.linalg.norm(direction, axis=-1)
    valid = norm > 1e-12 * max(float(norm.max(initial=0.0)), 1e-300)
    if not valid.any():
        out = np.zeros_like(direction)
        out[:, 1] = 1.0
        return out
    unit = np.zeros_like(direction)
    unit[valid] = direction[valid] / norm[valid, None]
    if not valid.all():
        idx = np.flatnonzero(valid)
        nearest = idx[np.clip(np.searchsorted(idx, np.arange(len(norm))), 0, len(idx) - 1)]
        unit[~valid] = unit[nearest[~valid]]
    return unit


def _to_y_up(axis: int, sign: float) -> np.ndarray:
    """Rotation taking the file's up axis (``sign`` * e_axis) to +Y (a proper rotation)."""
    if axis == 1:
        return np.eye(3) if sign > 0 else np.diag([1.0, -1.0, -1.0])
    if axis == 2:   # Z up: (x, y, z) -> (x, z, -y)
        r = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])
        return r if sign > 0 else np.diag([1.0, -1.0, -1.0]) @ r
    r = np.array([[0, 1.0, 0], [1.0, 0, 0], [0, 0, -1.0]])   # X up: (x, y, z) -> (y, x, -z)
    return r if sign > 0 else np.diag([1.0, -1.0, -1.0]) @ r


def _first_frame_is_inserted(points: np.ndarray) -> bool:
    """True if frame 0 is a pose that jumps away from an otherwise smooth clip (an inserted T-pose).

    The pose is taken relative to the pelvis; the jump 0 -> 1 must exceed 5x
    the largest (99th percentile) frame-to-frame change of the following
    frames and 5 % of the figure's size.
    """
    n = points.shape[0]
    if n < 4:
        return False
    pose = points[: min(n, 600)] - points[: min(n, 600), :1]
    steps = np.linalg.norm(np.diff(pose, axis=0), axis=-1).max(axis=-1)   # (F-1,)
    size = float(np.ptp(pose[1], axis=0).max())
    typical = float(np.percentile(steps[1:], 99))
    return bool(steps[0] > 5.0 * typical and steps[0] > 0.05 * size)
