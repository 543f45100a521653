"""Step 6 (paper 4.2): segment lengths from per-frame lower bounds, level by level.

Frame i is read as a virtual figure with its root on the image plane: root at
``P_1 = (x_1, y_1, f)`` in film millimetres, every length scaled by the frame's
virtual scale s'_i.  A segment whose parent joint P is known and whose child
projects to film point q has its child somewhere on the ray through q; the
shortest such segment is the distance from P to that ray (the paper's
``P_1 P_2,min`` perpendicular to ``O_c P_2'``), a *lower bound* of the true
virtual length.  Divided by s'_i, the bounds of all frames are comparable and
their maximum is the paper's estimate of the normalised length L.

Below the first level the parent is not known: with the parent's length L known,
the sphere of radius L s'_i round the grandparent meets the parent's ray in up to
two points, so a joint at level i has up to 2^(i-1) candidate positions (the
paper's 2^i poses); the frame's lower bound is the smallest over them.  Where
noise makes the ray miss the sphere, its closest point is used.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import JOINT_LEVEL, N_JOINTS, SEGMENTS


def rays(points: np.ndarray, focal_mm: float) -> np.ndarray:
    """Unit viewing rays (..., 3) of film points (..., 2)."""
    r = np.concatenate([points, np.full(points.shape[:-1] + (1,), float(focal_mm))], axis=-1)
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def distance_to_ray(cands: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Distance (F, C) from candidate points (F, C, 3) to the line through the origin along u (F, 3)."""
    along = np.einsum("fcx,fx->fc", cands, u)
    sq = np.einsum("fcx,fcx->fc", cands, cands) - along ** 2
    return np.sqrt(np.maximum(sq, 0.0))


def child_candidates(cands: np.ndarray, u: np.ndarray, length: np.ndarray) -> np.ndarray:
    """The two points (F, 2C, 3) on ray u at distance ``length`` (F,) from each parent candidate."""
    along = np.einsum("fcx,fx->fc", cands, u)
    sq = np.einsum("fcx,fcx->fc", cands, cands) - along ** 2
    half = np.sqrt(np.maximum(length[:, None] ** 2 - sq, 0.0))
    t = np.concatenate([along - half, along + half], axis=1)          # (F, 2C)
    t = np.maximum(t, 1e-6)                                           # stay in front of the camera
    return t[..., None] * u[:, None, :]


def frame_lower_bounds(points: np.ndarray, focal_mm: float, scale: np.ndarray,
                       lengths: np.ndarray | None = None, statistic=None) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame normalised lower bounds (F, 16) and the segment lengths (16,) they give.

    ``points`` are still-camera film points (F, 17, 2) in mm, NaN where missing;
    ``scale`` the virtual scale (F,), NaN for frames to skip.  ``statistic`` maps
    the finite normalised bounds of one segment to its length (default: max).
    If ``lengths`` is given, it is used for the branch positions instead of the
    estimates (tests use the truth to check a single level).
    """
    if statistic is None:
        statistic = np.max
    n = points.shape[0]
    u = rays(points, focal_mm)                                         # (F, 17, 3)
    cands: list[np.ndarray | None] = [None] * N_JOINTS
    root = np.concatenate([points[:, 0], np.full((n, 1), float(focal_mm))], axis=-1)
    cands[0] = root[:, None, :]
    bounds = np.full((n, len(SEGMENTS)), np.nan)
    est = np.full(len(SEGMENTS), np.nan)
    order = sorted(range(len(SEGMENTS)), key=lambda k: JOINT_LEVEL[SEGMENTS[k][1]])
    for k in order:
        parent, child = SEGMENTS[k]
        pc = cands[parent]
        lb = distance_to_ray(pc, u[:, child]).min(axis=1)               # NaN propagates
        norm = lb / scale
        bounds[:, k] = norm
        finite = norm[np.isfinite(norm)]
        est[k] = statistic(finite) if finite.size else np.nan
        length = est[k] if lengths is None else lengths[k]
        cands[child] = child_candidates(pc, u[:, child], np.full(n, length) * scale)
    return bounds, est
