"""Step 4b (paper 3.4): undo the camera motion, giving 2D data as seen by a still camera.

The camera turns about its centre of projection and zooms, so frame i's image is
frame 0's image mapped by the homography ``K_i R_i K_0^-1``; undoing it maps every
film point back with ``K_0 R_i^T K_i^-1``: lift the point to its ray
``(x, y, f_i)``, rotate the ray back to frame 0's axes, and project with the
initial focal length.  A zoom alone is then just a scale about the principal point.
"""

from __future__ import annotations

import numpy as np

from ..camera import pan_tilt_roll_matrix


def camera_rotations(pan_deg: np.ndarray, tilt_deg: np.ndarray) -> np.ndarray:
    """(F, 3, 3) ``R_i`` (``X_i = R_i X_0``) for absolute pan and tilt, no roll."""
    return pan_tilt_roll_matrix(np.asarray(pan_deg, dtype=float), np.asarray(tilt_deg, dtype=float))


def undo_camera(points: np.ndarray, rotations: np.ndarray, focal_mm: np.ndarray, focal0_mm: float) -> np.ndarray:
    """Film points (F, J, 2) of a moving camera -> film points of the still frame-0 camera."""
    pts = np.asarray(points, dtype=float)
    f = np.asarray(focal_mm, dtype=float)
    rays = np.concatenate([pts, np.broadcast_to(f[:, None, None], pts.shape[:2] + (1,))], axis=-1)
    back = np.einsum("fji,fkj->fki", rotations, rays)     # R_i^T @ ray
    return focal0_mm * back[..., :2] / back[..., 2:3]


def redo_camera(points0: np.ndarray, rotations: np.ndarray, focal_mm: np.ndarray, focal0_mm: float) -> np.ndarray:
    """Inverse of :func:`undo_camera` (used by tests and for reprojection)."""
    pts = np.asarray(points0, dtype=float)
    rays = np.concatenate([pts, np.full(pts.shape[:2] + (1,), float(focal0_mm))], axis=-1)
    fwd = np.einsum("fij,fkj->fki", rotations, rays)
    f = np.asarray(focal_mm, dtype=float)
    return f[:, None, None] * fwd[..., :2] / fwd[..., 2:3]
