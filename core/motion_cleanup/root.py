"""A steadier root: the figure's distance from the camera smoothed, its direction left to the picture.

The camera model rotates about a fixed centre (the origin of the frame-0 camera axes), so where the
person stands along the line of sight from that centre is what the picture says least about: it
comes from the figure's size alone, and jitters.  Sliding the whole figure along the pelvis' line of
sight keeps the pelvis on its image point and every bone its length, and changes the figure's image
only by the ratio of the distances; so the distance is smoothed (a Gaussian of ``sigma_s`` seconds)
and the direction is not touched.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from ..skeleton import JOINT_INDEX


def smooth_root_distance(joints: np.ndarray, fps: float, sigma_s: float) -> tuple[np.ndarray, float]:
    """``joints`` (F, 17, 3) slid along the pelvis' ray so its distance from the camera centre is smoothed;
    and the largest slide (m)."""
    j = np.array(joints, dtype=float, copy=True)
    sigma = sigma_s * fps
    if sigma <= 0 or j.shape[0] < 3:
        return j, 0.0
    pelvis = j[:, JOINT_INDEX["pelvis"]]
    dist = np.linalg.norm(pelvis, axis=-1)
    smooth = gaussian_filter1d(dist, sigma, mode="nearest")
    ray = pelvis / np.maximum(dist, 1e-9)[:, None]
    shift = (smooth - dist)[:, None] * ray
    return j + shift[:, None, :], float(np.abs(smooth - dist).max())
