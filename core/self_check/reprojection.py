"""Reprojection of an estimate's 3D joints through its own camera, against the 2D tracks."""

from __future__ import annotations

import numpy as np

from ..camera import project_to_pixels, rotation_matrix
from ..result import Estimate
from ..skeleton import N_JOINTS
from ..tracks import Tracks


def camera_points(est: Estimate) -> tuple[np.ndarray, np.ndarray]:
    """(each frame's joints in that frame's camera axes (F, 17, 3), NaN in frames without 3D joints;
    focal lengths (F,) mm)."""
    joints = np.array([f.joints_3d if f.joints_3d is not None else np.full((N_JOINTS, 3), np.nan)
                       for f in est.frames], dtype=float)                       # frame-0 camera axes
    rot = rotation_matrix(np.array([f.rotvec_deg for f in est.frames], dtype=float))
    focal = np.array([f.focal_mm for f in est.frames], dtype=float)
    return np.einsum("fab,fjb->fja", rot, joints), focal


def project_in_front(cam: np.ndarray, focal: np.ndarray, image_size) -> tuple[np.ndarray, np.ndarray]:
    """(pixels (F, 17, 2), in front (F, 17) bool) of camera-axes points (F, 17, 3); points behind the
    camera (or on it) are projected as if on the axis, and flagged."""
    ok = cam[..., 2] > 1e-3
    safe = np.where(ok[..., None], cam, np.array([0.0, 0.0, 1.0]))
    return project_to_pixels(safe, focal[:, None], image_size), ok


def reprojection_residuals(tracks: Tracks, cam: np.ndarray, focal: np.ndarray) -> np.ndarray:
    """(F, 17) pixel distance between each observed joint and its reprojection (NaN where unobserved),
    from :func:`camera_points`."""
    uv, ok = project_in_front(cam, focal, tracks.image_size)
    err = np.linalg.norm(uv - tracks.xy, axis=-1)
    return np.where(ok & tracks.present, err, np.nan)
