"""Least-squares polish of a single-image pose: every joint fitted to its image point at once.

Taylor's construction places each child on its own viewing ray at its bone's length from its
parent, so one joint's image noise moves every joint below it, and a segment nearly parallel to the
image amplifies it (its depth is ``sqrt(l^2 - d^2)``).  The polish keeps what Taylor's method chose
(the depth signs, as the starting point of a local solve, and the scale, by holding the root's
depth) and moves all joints together to fit all image points under perspective with every bone at
its length, so the noise is shared out instead of handed down the chain.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ..skeleton import N_JOINTS, SEGMENTS

#: bone lengths held to this (metres); the root's depth to this (metres)
LENGTH_SIGMA_M = 0.001
ROOT_DEPTH_SIGMA_M = 0.001


def refine_pose(joints: np.ndarray, uv: np.ndarray, seg_len: np.ndarray, focal_px: float,
                noise_px: float = 1.0) -> np.ndarray:
    """The polished (17, 3) pose; ``joints`` from Taylor's perspective construction, ``uv`` (17, 2) pixels from
    the principal point (NaN where missing).  Joints without a position are left NaN."""
    placed = np.isfinite(joints).all(axis=1)
    seen = placed & np.isfinite(uv).all(axis=1)
    bones = [(k, p, c) for k, (p, c) in enumerate(SEGMENTS) if placed[p] and placed[c]]
    if seen.sum() < 3 or not placed[0]:
        return joints
    idx = np.flatnonzero(placed)
    slot = {j: i for i, j in enumerate(idx)}
    z_root = float(joints[0, 2])
    f = float(focal_px)

    def residuals(x):
        X = x.reshape(-1, 3)
        out = []
        for j in np.flatnonzero(seen):
            p = X[slot[j]]
            out.append((f * p[:2] / max(p[2], 1e-6) - uv[j]) / noise_px)
        for k, p, c in bones:
            out.append([(np.linalg.norm(X[slot[c]] - X[slot[p]]) - seg_len[k]) / LENGTH_SIGMA_M])
        out.append([(X[slot[0], 2] - z_root) / ROOT_DEPTH_SIGMA_M])
        return np.concatenate(out)

    fit = least_squares(residuals, joints[idx].ravel(), method="lm", max_nfev=200)
    out = np.full((N_JOINTS, 3), np.nan)
    out[idx] = fit.x.reshape(-1, 3)
    return out
