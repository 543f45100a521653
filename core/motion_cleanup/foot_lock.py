"""Planted feet held still in the world: each contact's ankle is pinned to one place by bending its leg.

For every contact (:mod:`.contacts`) the ankle's place is the median of where the solve put it over
the contact, and the ankle is held there.  Before and after the contact the ankle keeps the solve's
motion plus the offset the lock gave it on the contact's first (last) frame, eased (smoothstep) to
nothing over ``blend_s``, so the foot neither pops in nor pops out at release.  The leg then reaches
the new ankle by two-bone inverse kinematics: the hip stays, the thigh and shin keep their lengths,
the knee stays in the plane it bent in.  A place out of the leg's reach is approached as near as the
leg allows (the rest is left, not forced).
"""

from __future__ import annotations

import numpy as np

from ..runs import runs
from ..skeleton import JOINT_INDEX

LEGS = {0: (JOINT_INDEX["l_hip"], JOINT_INDEX["l_knee"], JOINT_INDEX["l_ankle"]),
        1: (JOINT_INDEX["r_hip"], JOINT_INDEX["r_knee"], JOINT_INDEX["r_ankle"])}


def smoothstep(u: np.ndarray) -> np.ndarray:
    """0 to 1 over ``u`` in [0, 1] with no jump in speed at either end: the eases in and out of a hold."""
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def lock_corrections(ankle: np.ndarray, contact: np.ndarray, blend_frames: int) -> np.ndarray:
    """(F, 3) move of one ankle (F, 3) that pins it over its contacts (F,) bool, eased in and out.

    During a contact the move takes the ankle to the contact's place.  Before and after it the move is
    the one of the contact's first (last) frame, a constant offset, eased (smoothstep) to nothing over
    ``blend_frames``: the foot keeps the solve's own motion as it lifts off, and only the small offset
    fades (easing towards the *place* instead would hold a lifting foot back and let it catch up in a
    jump).  Where two eases overlap the nearer contact wins."""
    n = ankle.shape[0]
    weight = np.zeros(n)
    move = np.zeros((n, 3))
    for a, end in runs(contact):
        b = end - 1                                    # the contact's last frame
        place = np.median(ankle[a:b + 1], axis=0)
        move[a:b + 1] = place - ankle[a:b + 1]
        weight[a:b + 1] = 1.0
        before = np.arange(max(0, a - blend_frames), a)
        after = np.arange(b + 1, min(n, b + blend_frames + 1))
        for edge, idx in ((a, before), (b, after)):
            if idx.size == 0:
                continue
            w = 1.0 - smoothstep(np.abs(idx - edge) / (blend_frames + 1.0))
            better = w > weight[idx]
            weight[idx[better]] = w[better]
            move[idx[better]] = w[better, None] * (place - ankle[edge])
    return move


def two_bone_ik(hip: np.ndarray, knee: np.ndarray, ankle: np.ndarray,
                goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """New (knee, ankle) (F, 3) reaching towards ``goal`` from a fixed ``hip``, bone lengths and bend plane kept."""
    l1 = np.linalg.norm(knee - hip, axis=-1)
    l2 = np.linalg.norm(ankle - knee, axis=-1)
    to_goal = goal - hip
    d = np.linalg.norm(to_goal, axis=-1)
    d_ok = np.clip(d, np.abs(l1 - l2) + 1e-6, l1 + l2 - 1e-6)
    u = to_goal / np.maximum(d, 1e-9)[:, None]
    # the knee's side: the old knee off the hip->goal line (else the old hip->ankle line's normal)
    pole = (knee - hip) - u * np.sum((knee - hip) * u, axis=-1, keepdims=True)
    pn = np.linalg.norm(pole, axis=-1)
    fallback = np.cross(u, np.array([1.0, 0.0, 0.0]))
    pole = np.where(pn[:, None] > 1e-6, pole, fallback)
    v = pole / np.maximum(np.linalg.norm(pole, axis=-1, keepdims=True), 1e-12)
    along = (l1 ** 2 - l2 ** 2 + d_ok ** 2) / (2.0 * d_ok)
    across = np.sqrt(np.maximum(l1 ** 2 - along ** 2, 0.0))
    new_knee = hip + u * along[:, None] + v * across[:, None]
    new_ankle = hip + u * d_ok[:, None]
    return new_knee, new_ankle


def lock_feet(joints: np.ndarray, contacts: np.ndarray, fps: float, blend_s: float) -> tuple[np.ndarray, dict]:
    """``joints`` (F, 17, 3) in static axes with every contact's ankle pinned (module docstring); and a
    report: contacts per foot, frames moved, the largest ankle move (m) and how far out of reach (m)."""
    out = np.array(joints, dtype=float, copy=True)
    blend = max(0, int(round(blend_s * fps)))
    report = {"contacts": [0, 0], "frames_locked": [0, 0], "max_move_m": 0.0, "unreached_m": 0.0}
    for s, (h, k, a) in LEGS.items():
        move = lock_corrections(out[:, a], contacts[:, s], blend)
        sel = contacts[:, s].copy()
        sel |= np.any(move != 0.0, axis=1)
        report["contacts"][s] = len(runs(contacts[:, s]))
        report["frames_locked"][s] = int(contacts[:, s].sum())
        if not sel.any():
            continue
        goal = out[sel, a] + move[sel]
        knee, ankle = two_bone_ik(out[sel, h], out[sel, k], out[sel, a], goal)
        report["max_move_m"] = max(report["max_move_m"], float(np.linalg.norm(ankle - out[sel, a], axis=-1).max()))
        report["unreached_m"] = max(report["unreached_m"], float(np.linalg.norm(ankle - goal, axis=-1).max()))
        out[sel, k], out[sel, a] = knee, ankle
    return out, report
