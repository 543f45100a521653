"""Clean curves for the baked keys: Euler angles without jumps, and fewer keys within an error bound.

The retargeting bakes a key on every frame.  Rigs whose bones rotate in Euler modes need angles that
never jump by 360 degrees (or flip to the equivalent triple) between frames, or interpolation spins the
bone; and an animator editing the result wants keys only where the motion needs them.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def sign_continuous(q: np.ndarray) -> np.ndarray:
    """Quaternions (F, 4), each one's sign chosen on its predecessor's side (the same rotations), so
    interpolation between neighbouring keys takes the short way."""
    q = np.array(q, dtype=float)
    flip = np.cumsum(np.concatenate([[0], (np.sum(q[1:] * q[:-1], axis=1) < 0).astype(int)])) % 2 == 1
    q[flip] *= -1
    return q


def euler_continuous(q_wxyz: np.ndarray, order: str = "XYZ") -> np.ndarray:
    """(F, 3) Euler angles (radians) of quaternions (F, 4) (w, x, y, z) for a bone in Blender's Euler
    ``order`` ('XYZ': X applied first), returned as Blender stores them, (x, y, z) whatever the order;
    each frame's triple is the one of its two equivalents (and 2 pi shifts) nearest the previous frame's."""
    q = np.asarray(q_wxyz, dtype=float)
    seq = order.lower()                     # Blender 'XYZ' = R_z R_y R_x = scipy's extrinsic 'xyz'
    angles = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_euler(seq)      # columns in the order's sequence
    out = angles.copy()
    for i in range(1, len(out)):
        prev = out[i - 1]
        a = angles[i]
        alt = np.array([a[0] + np.pi, np.pi - a[1], a[2] + np.pi])     # the same rotation (Tait-Bryan)
        best = None
        for cand in (a, alt):
            c = cand + 2 * np.pi * np.round((prev - cand) / (2 * np.pi))
            if best is None or np.abs(c - prev).sum() < np.abs(best - prev).sum():
                best = c
        out[i] = best
    xyz = np.empty_like(out)
    for k, axis in enumerate(seq):
        xyz[:, "xyz".index(axis)] = out[:, k]
    return xyz


def reduce_keys(values: np.ndarray, max_error: float) -> np.ndarray:
    """Indices of the keys to keep so that linear interpolation between them stays within ``max_error``
    of every value (F, C) in every channel (Ramer-Douglas-Peucker); first and last are always kept."""
    v = np.asarray(values, dtype=float)
    if v.ndim == 1:
        v = v[:, None]
    n = len(v)
    if n <= 2 or max_error <= 0:
        return np.arange(n)
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        t = (np.arange(a + 1, b) - a) / (b - a)
        line = v[a] + t[:, None] * (v[b] - v[a])
        err = np.abs(v[a + 1:b] - line).max(axis=1)
        k = int(np.argmax(err))
        if err[k] > max_error:
            m = a + 1 + k
            keep[m] = True
            stack += [(a, m), (m, b)]
    return np.flatnonzero(keep)


def quaternion_angle_deg(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Angle (degrees) between rotations given as quaternions (..., 4), either sign."""
    a, b = (np.asarray(q, dtype=float) for q in (q1, q2))
    dot = np.abs(np.sum(a * b, axis=-1)) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(2 * np.arccos(np.clip(dot, -1.0, 1.0)))


def reduce_quaternion_keys(q: np.ndarray, max_deg: float) -> np.ndarray:
    """Key indices for quaternions (F, 4) such that the linearly interpolated, normalised quaternion stays
    within about ``max_deg`` of every frame (the bound is checked and tightened until it holds)."""
    q = np.asarray(q, dtype=float)
    tol = np.sin(np.radians(max_deg) / 4)
    for _ in range(8):
        keep = reduce_keys(q, tol)
        if max_deg <= 0 or interpolation_error_deg(q, keep) <= max_deg:
            return keep
        tol *= 0.5
    return np.arange(len(q))


def interpolation_error_deg(q: np.ndarray, keep: np.ndarray) -> float:
    """Largest angle between every frame's quaternion and the linear interpolation of the kept keys."""
    frames = np.arange(len(q))
    interp = np.stack([np.interp(frames, keep, q[keep, c]) for c in range(q.shape[1])], axis=1)
    return float(quaternion_angle_deg(interp, q).max()) if len(q) else 0.0
