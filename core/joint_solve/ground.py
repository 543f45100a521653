"""Floor plane and up direction from the planted feet -> ``world_from_cam0``.

While a foot is planted its ankle sits a fixed height above the floor
(:data:`core.skeleton.ANKLE_HEIGHT_FRACTION` of stature).  The planted ankle
positions over the clip (in static frame-0 axes) therefore lie on a plane
parallel to the floor.  When they span two directions (turns, side steps)
the plane's normal is the up direction; when they lie on a line (a straight
walk) only the line is known, and the body's own vertical (ankles to neck
while standing on a foot) fixes the rotation about that line.  The body
vertical also orients the normal (up, not down) and is the fallback when
there is no planted foot at all.

The result maps frame-0 camera coordinates (x right, y down, z forward) to a
Blender-style world: Z up, floor z = 0, X along the camera's right
direction projected on the floor, origin on the floor below frame 0's pelvis.

Why this fit and not the joint solve's own floor unknowns (up vector and offset, which steer its
floor and upright terms): measured on the 15 clips (14 shared + built-in walk, 900 frames, 1 px), the
angle between the estimated and the true up direction has a median of 3.2 degrees with this fit and
5.9 with the solver's (worse on 10 of 15 clips; 21 degrees on ``milad``).
Both were 23-26 degrees off on jogging and side-skip, whose camera is wrong (see
``docs/joint_solve_findings.md``): a wrong camera track smears the planted ankles (in frame-0 axes)
across a tilted plane, and the body's own vertical then disagrees with it, so beyond
:data:`FLOOR_BODY_MAX_DEG` the body's vertical is used.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import ANKLE_HEIGHT_FRACTION, FEET, JOINT_INDEX

PLANAR_RATIO = 0.15   # second / first singular value above which footprints span a plane
#: Largest angle (degrees) between the planted-ankle plane's normal and the body's own vertical that is
#: believed; beyond it the body's vertical is the up direction, with a warning.  A person standing and
#: walking keeps the ankles-to-neck line near the floor's normal over a clip, so a larger angle means the
#: planted ankles were put in the wrong places, which a wrong camera track does.  Measured with the joint
#: method on the 15 clips (900 frames max, pan/tilt/zoom, 1 px): the angle is 0.0-9.6 degrees on 13 clips
#: (9.6 on the martial arts, the kick and the dance, whose bodies lean), and 18.1 and 19.8 on side-skip and
#: jogging, where the camera is wrong: there the plane's normal is 25.1 and 22.5 degrees from the true up,
#: the body's vertical 7.0 and 8.9.
FLOOR_BODY_MAX_DEG = 15.0
#: With the camera from background points (right to 0.1-0.3 degrees) the fallback still fires, and is still
#: right: on the tune half of ``bench/robust_bench.py`` (5 clips x 4 draws x target and broad, 12 points) the
#: three clips over the limit had the planted-ankle plane 9-18 degrees from the true up and the body's
#: vertical 5-8: the stance had put planted feet where none stood.


def _unit(v):
    return v / max(float(np.linalg.norm(v)), 1e-12)


def body_up(joints: np.ndarray, stance: np.ndarray) -> np.ndarray:
    """Mean direction from the ankles' midpoint to the neck (frames with a planted foot if any)."""
    mid = 0.5 * (joints[:, FEET["l"]] + joints[:, FEET["r"]])
    v = joints[:, JOINT_INDEX["neck"]] - mid
    sel = stance >= 0
    if sel.sum() >= 3:
        v = v[sel]
    v = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)
    return _unit(v.mean(axis=0))


def planted_points(joints: np.ndarray, stance: np.ndarray) -> np.ndarray:
    pts = []
    for side, code in (("l", 0), ("r", 1)):
        sel = stance == code
        if sel.any():
            pts.append(joints[sel, FEET[side]])
    return np.concatenate(pts) if pts else np.zeros((0, 3))


def world_from_cam0(joints: np.ndarray, stance: np.ndarray, height_m: float,
                    camera_known: bool = False) -> tuple[np.ndarray, list[str]]:
    """4x4 world-from-camera-0 matrix and warnings.  ``camera_known``: the camera came from elsewhere (the
    background, calibrated views), so a floor at odds with the body blames the planted feet found, not it."""
    warnings: list[str] = []
    up_body = body_up(joints, stance)
    pts = planted_points(joints, stance)
    up = up_body
    if len(pts) >= 3:
        c = pts.mean(axis=0)
        _, sv, vt = np.linalg.svd(pts - c, full_matrices=False)
        if sv[0] > 1e-6 and sv[1] / sv[0] > PLANAR_RATIO:
            up = vt[2] * np.sign(vt[2] @ up_body)
        elif sv[0] > 1e-6:
            line = vt[0]
            up = _unit(up_body - line * (line @ up_body))
        tilt = float(np.degrees(np.arccos(np.clip(up @ up_body, -1.0, 1.0))))
        if tilt > FLOOR_BODY_MAX_DEG:
            if camera_known:
                cause = ("the camera came from the background or other views, so the feet found planted are "
                         "the doubt - check the stance against the footage")
            else:
                cause = ("a wrong camera track puts planted feet in the wrong places - check the camera against "
                         "the footage")
            warnings.append(f"floor: the planted feet lie on a plane tilted {tilt:.0f} degrees from the body's "
                            f"vertical, so the body's vertical is used as up; {cause}")
            up = up_body
        ankle_plane = float(np.median(pts @ up))
    else:
        warnings.append("no planted foot found: floor placed below the lowest ankle, up from the body")
        ankle_plane = float(np.min(joints[:, [FEET["l"], FEET["r"]]].reshape(-1, 3) @ up))
    floor = ankle_plane - ANKLE_HEIGHT_FRACTION * height_m
    x_axis = np.array([1.0, 0.0, 0.0])
    x_axis = _unit(x_axis - up * (x_axis @ up))
    y_axis = np.cross(up, x_axis)
    rot = np.stack([x_axis, y_axis, up])          # rows: world axes in camera-0 coordinates
    pelvis = joints[0, JOINT_INDEX["pelvis"]]
    origin = pelvis - up * (pelvis @ up - floor)
    m = np.eye(4)
    m[:3, :3] = rot
    m[:3, 3] = -rot @ origin
    return m, warnings
