"""Reprojection of an estimate's 3D joints through its own camera, against the 2D tracks."""

from __future__ import annotations

import numpy as np

from ..camera import project_to_pixels, rotation_matrix
from ..result import Estimate
from ..tracks import Tracks


def reprojection_residuals(est: Estimate, tracks: Tracks) -> np.ndarray | None:
    """(F, 17) pixel distance between each observed joint and its reprojection (NaN where unobserved);
    None when the estimate has no 3D joints."""
    if any(f.joints_3d is None for f in est.frames) or len(est.frames) != tracks.n_frames:
        return None
    joints = np.array([f.joints_3d for f in est.frames], dtype=float)          # frame-0 camera axes
    rot = rotation_matrix(np.array([f.rotvec_deg for f in est.frames], dtype=float))
    focal = np.array([f.focal_mm for f in est.frames], dtype=float)
    cam = np.einsum("fab,fjb->fja", rot, joints)
    ok = cam[..., 2] > 1e-3
    safe = np.where(ok[..., None], cam, np.array([0.0, 0.0, 1.0]))
    uv = project_to_pixels(safe, focal[:, None], tracks.image_size)
    err = np.linalg.norm(uv - tracks.xy, axis=-1)
    return np.where(ok & tracks.present, err, np.nan)
