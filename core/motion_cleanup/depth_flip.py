"""An animator's correction: one bone turned to its other side in depth over a span of frames.

Why: a bone seen in one picture has two places that draw it the same (Taylor's two depth signs: its
far end nearer the camera than its near end, or farther). The solve chooses one per frame, and where
it chose wrong an animator sees a limb mirrored in depth (an elbow bent backwards, a thigh swung
forwards) over a stretch of frames. Re-solving cannot be told which; the animator can. This puts
the bone's end on the other place along the same line of sight, at the bone's own length, on every
frame of the span: the picture (the joints' reprojection) and every bone's length stay exactly as
they were, and the bones below it keep their own depth sign from their new start.

A bone lying in the picture's plane has one place only (its two candidates meet): such frames are left
as they are and counted. Planted feet are not held again: a flipped thigh or shin moves the ankle in
depth, so a foot the motion cleanup held may slide on the flipped frames.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import rotation_matrix
from ..errors import InputError
from ..joint_solve.taylor import child_candidates
from ..result import Estimate
from ..skeleton import JOINT_INDEX, JOINTS, SEGMENTS

#: Two candidates closer than this (metres) are one place: the bone lies in the picture's plane.
SAME_PLACE_M = 1e-4


def segment_of(bone: str) -> int:
    """The segment index of a bone named by the joint it ends at (``"l_wrist"``: the left forearm)."""
    child = JOINT_INDEX.get(bone)
    if child is None or child == 0:
        names = ", ".join(JOINTS[1:])
        raise InputError(f"no bone ends at {bone!r}: name it by the joint it ends at ({names})")
    return next(s for s, (_, c) in enumerate(SEGMENTS) if c == child)


def _below(segment: int) -> list[int]:
    """The segments under ``segment`` (its child's descendants), parents before children."""
    joints = {SEGMENTS[segment][1]}
    out = []
    for s, (p, c) in enumerate(SEGMENTS):
        if p in joints:
            joints.add(c)
            out.append(s)
    return out


def _sides(parent: np.ndarray, child: np.ndarray, length: float, start: np.ndarray | None = None):
    """(near, far, whether ``child`` is the far one): the two places on ``child``'s ray at ``length`` from
    ``parent`` (camera axes), and with ``start`` the two from that moved parent instead."""
    ray = child / np.linalg.norm(child)
    near, far, _ = child_candidates(parent, ray, length)
    was_far = np.linalg.norm(child - far) < np.linalg.norm(child - near)
    if start is not None:
        near, far, _ = child_candidates(start, ray, length)
    return near, far, was_far


def flip_depth(est: Estimate, bone: str, first: int, last: int) -> tuple[Estimate, dict]:
    """``est`` with the bone ending at joint ``bone`` turned to its other side in depth on frames ``first`` to
    ``last`` (0-based, inclusive), and a report: ``frames`` flipped, ``in_plane`` (frames where the bone
    lies in the picture's plane, left as they were), ``largest_move_m`` (of any joint).

    Works in each frame's camera axes (``rotvec_deg``), so a moving camera is no matter; frames without 3D
    joints are skipped. Returns a new estimate (``est`` is not changed) whose ``diagnostics["depth_flips"]``
    lists every such correction made to it, this one last."""
    segment = segment_of(bone)
    n = len(est.frames)
    if not (0 <= first <= last < n):
        raise InputError(f"frames {first}-{last} are not in the estimate's 0-{n - 1}")
    if not any(est.frames[i].joints_3d is not None for i in range(first, last + 1)):
        raise InputError(f"the estimate has no 3D joints on frames {first}-{last}: run the joint method")
    below = _below(segment)
    parent, child = SEGMENTS[segment]
    frames = list(est.frames)
    flipped = in_plane = 0
    largest = 0.0
    for i in range(first, last + 1):
        fr = frames[i]
        if fr.joints_3d is None:
            continue
        R = rotation_matrix(np.asarray(fr.rotvec_deg, dtype=float))
        old = np.asarray(fr.joints_3d, dtype=float) @ R.T                    # camera axes of frame i
        new = old.copy()
        near, far, was_far = _sides(old[parent], old[child], np.linalg.norm(old[child] - old[parent]))
        if np.linalg.norm(far - near) < SAME_PLACE_M:          # one place only: the bone is in the picture's plane
            in_plane += 1
            continue
        new[child] = near if was_far else far                  # the other place
        for s in below:                                        # the same side, from the moved parent
            p, c = SEGMENTS[s]
            near, far, was_far = _sides(old[p], old[c], np.linalg.norm(old[c] - old[p]), start=new[p])
            new[c] = far if was_far else near
        largest = max(largest, float(np.max(np.linalg.norm(new - old, axis=1))))
        frames[i] = dataclasses.replace(fr, joints_3d=(new @ R).tolist())    # back to frame 0's axes
        flipped += 1
    report = {"bone": bone, "first": first, "last": last, "frames": flipped, "in_plane": in_plane,
              "largest_move_m": largest}
    # the estimate says it was corrected by hand; its self-check's reprojection figures still hold (the
    # picture is the same), its pose prior's doubts were of the poses as solved
    diagnostics = dict(est.diagnostics or {})
    diagnostics["depth_flips"] = list(diagnostics.get("depth_flips", [])) + [report]
    return dataclasses.replace(est, frames=frames, diagnostics=diagnostics), report
