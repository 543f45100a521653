"""Least-squares polish of a single-image pose: every joint fitted to its image point at once.

Taylor's construction places each child on its own viewing ray at its bone's length from its
parent, so one joint's image noise moves every joint below it, and a segment nearly parallel to the
image amplifies it (its depth is ``sqrt(l^2 - d^2)``).  The polish keeps what Taylor's method chose
(the depth signs, as the starting point of a local solve, and the scale, by holding the root's
depth) and moves all joints together to fit all image points under perspective with every bone at
its length, so the noise is shared out instead of handed down the chain.

The pose lifter's bone directions (:mod:`core.motion_prior.lifter`, the same cue that helps choose the
signs) join the polish as a soft pull on each bone whose sign the user did not hold, as they do in the
video solve (``core.joint_solve.pipeline.SOLVE_CUE_SIGMA``): a bone near the picture's plane otherwise
settles wherever the image points leave it, often through the plane on the mirror side.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ..skeleton import N_JOINTS, SEGMENTS

#: bone lengths held to this (metres); the root's depth to this (metres)
LENGTH_SIGMA_M = 0.001
ROOT_DEPTH_SIGMA_M = 0.001
#: Unit-vector sigma of the lifter's pull on a bone's direction; None: no pull.  Chosen on the tune half of
#: ``bench/single_image_bench.py --half tune --every 10 --max-frames 300`` (96 frames; perspective, true
#: focal length and lengths; P-MPJPE median / mean, frames with a mirrored limb), at 0 px: none 46.1 / 51.3
#: mm, 18.8 %; 0.4 44.5 / 50.6, 17.7 %; 0.2 43.7 / 50.2, 15.6 %; 0.15 43.8 / 49.8, 14.6 %; 0.1 45.4 / 50.3,
#: 13.5 %; 0.08 45.2 / 50.6, 12.5 %; 0.05 46.0 / 51.9, 11.5 %; at 1 px: none 70.5 / 70.6 mm, 21.9 %; 0.1
#: 59.0 / 59.7, 13.5 %; 0.08 56.1 / 59.0, 12.5 %.
CUE_SIGMA: float | None = 0.08


def refine_pose(joints: np.ndarray, uv: np.ndarray, seg_len: np.ndarray, focal_px: float,
                noise_px: float = 1.0, cue: np.ndarray | None = None) -> np.ndarray:
    """The polished (17, 3) pose; ``joints`` from Taylor's perspective construction, ``uv`` (17, 2) pixels from
    the principal point (NaN where missing).  Joints without a position are left NaN.  ``cue`` (16, 3): unit
    bone directions in the camera's axes to lean towards (:data:`CUE_SIGMA`), NaN rows for none."""
    placed = np.isfinite(joints).all(axis=1)
    seen = placed & np.isfinite(uv).all(axis=1)
    bones = [(k, p, c) for k, (p, c) in enumerate(SEGMENTS) if placed[p] and placed[c]]
    if seen.sum() < 3 or not placed[0]:
        return joints
    idx = np.flatnonzero(placed)
    slot = {j: i for i, j in enumerate(idx)}
    z_root = float(joints[0, 2])
    f = float(focal_px)
    cued = [] if cue is None or CUE_SIGMA is None else [(k, p, c) for k, p, c in bones if np.isfinite(cue[k]).all()]

    def residuals(x):
        X = x.reshape(-1, 3)
        out = []
        for j in np.flatnonzero(seen):
            p = X[slot[j]]
            out.append((f * p[:2] / max(p[2], 1e-6) - uv[j]) / noise_px)
        for k, p, c in bones:
            out.append([(np.linalg.norm(X[slot[c]] - X[slot[p]]) - seg_len[k]) / LENGTH_SIGMA_M])
        out.append([(X[slot[0], 2] - z_root) / ROOT_DEPTH_SIGMA_M])
        for k, p, c in cued:
            v = X[slot[c]] - X[slot[p]]
            out.append((v / max(np.linalg.norm(v), 1e-9) - cue[k]) / CUE_SIGMA)
        return np.concatenate(out)

    fit = least_squares(residuals, joints[idx].ravel(), method="lm", max_nfev=200)
    out = np.full((N_JOINTS, 3), np.nan)
    out[idx] = fit.x.reshape(-1, 3)
    return out
