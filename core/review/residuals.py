"""Each joint's track against the solved joint seen through the solved camera: the residual lines.

The lines are what an animator looks at in the camera view to judge a fit: where the 2D track is,
where the 3D answer lands in the image, and how far apart they are, coloured by that distance.
"""

from __future__ import annotations

import numpy as np

from ..camera import rotation_matrix
from ..result import Estimate
from ..self_check.reprojection import project_in_front

#: Residual colours: green at 0, yellow at ``limit``, red at twice ``limit`` and above (RGBA).
GOOD = (0.15, 0.85, 0.25, 1.0)
FAIR = (1.0, 0.85, 0.1, 1.0)
BAD = (1.0, 0.15, 0.1, 1.0)
#: Residual (pixels) shown yellow when the caller has no better limit (the self-check's fit floor).
DEFAULT_LIMIT_PX = 4.0


def reprojected_pixels(est: Estimate, image_size) -> np.ndarray:
    """(F, 17, 2) pixels where each frame's solved joints land through that frame's camera.

    NaN for frames without 3D joints and for joints behind the camera.
    """
    n = len(est.frames)
    out = np.full((n, 17, 2), np.nan)
    idx = [i for i, fr in enumerate(est.frames) if fr.joints_3d is not None]
    if not idx:
        return out
    joints = np.array([est.frames[i].joints_3d for i in idx], dtype=float)         # frame-0 camera axes
    if joints.shape[1:] != (17, 3):
        raise ValueError(f"joints_3d must be 17 x [x, y, z], got {joints.shape[1:]}")
    rot = rotation_matrix(np.array([est.frames[i].rotvec_deg for i in idx], dtype=float))
    focal = np.array([est.frames[i].focal_mm for i in idx], dtype=float)
    cam = np.einsum("fab,fjb->fja", rot, joints)
    uv, front = project_in_front(cam, focal, image_size)
    front &= np.isfinite(cam).all(axis=-1)
    out[idx] = np.where(front[..., None], uv, np.nan)
    return out


def residual_lines(track_xy: np.ndarray, present: np.ndarray, reprojected: np.ndarray):
    """(tracks (F, 17, 2), reprojections (F, 17, 2), residuals (F, 17) px, drawn (F, 17) bool).

    A joint's line is drawn where both ends exist: the joint was tracked and the frame was solved.
    """
    track_xy = np.asarray(track_xy, dtype=float)
    reprojected = np.asarray(reprojected, dtype=float)
    drawn = np.asarray(present, dtype=bool) & np.isfinite(track_xy).all(-1) & np.isfinite(reprojected).all(-1)
    residual = np.where(drawn, np.linalg.norm(np.nan_to_num(track_xy - reprojected), axis=-1), np.nan)
    return track_xy, reprojected, residual, drawn


def residual_colours(residual_px, limit_px: float = DEFAULT_LIMIT_PX) -> np.ndarray:
    """RGBA (..., 4) per residual: green -> yellow at ``limit_px`` -> red at twice it (NaN: grey)."""
    r = np.asarray(residual_px, dtype=float)
    t = np.clip(np.nan_to_num(r, nan=0.0) / max(float(limit_px), 1e-9), 0.0, 2.0)
    good, fair, bad = (np.array(c) for c in (GOOD, FAIR, BAD))
    low = good + (fair - good) * np.clip(t, 0.0, 1.0)[..., None]
    out = np.where((t <= 1.0)[..., None], low, fair + (bad - fair) * np.clip(t - 1.0, 0.0, 1.0)[..., None])
    out[~np.isfinite(r)] = (0.5, 0.5, 0.5, 0.6)
    return out
