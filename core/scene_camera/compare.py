"""How far an estimate's camera is from another solve of the same clip (Blender's own camera solve).

Both cameras are compared relative to the first frame the other solve covers, so neither's frame-0
convention matters: per-frame angle between the relative rotations, and the focal lengths' ratio.
"""

from __future__ import annotations

import numpy as np

from ..camera import rotation_matrix


def compare_cameras(rotvec_deg: np.ndarray, focal_mm: np.ndarray, other: dict) -> dict | None:
    """Differences of the camera (``rotvec_deg`` (F, 3), ``focal_mm`` (F,), frame-0 axes) from ``other``:
    ``{"frames": (k,) 0-based frames, "rotvec_deg": (k, 3) relative to its first frame's camera,
    "focal_mm": one value or None}``.  None when the two share fewer than two frames."""
    frames = np.asarray(other["frames"], dtype=int)
    inside = (frames >= 0) & (frames < len(rotvec_deg))
    if inside.sum() < 2:
        return None
    frames = frames[inside]
    R_other = rotation_matrix(np.asarray(other["rotvec_deg"], dtype=float)[inside])
    R_est = rotation_matrix(np.asarray(rotvec_deg, dtype=float)[frames])
    ref = int(np.flatnonzero(inside)[0])
    R_other_ref = rotation_matrix(np.asarray(other["rotvec_deg"], dtype=float)[ref])
    rel_est = R_est @ R_est[0].T
    rel_other = R_other @ R_other_ref.T
    diff = rel_est @ np.transpose(rel_other, (0, 2, 1))
    angle = np.degrees(np.arccos(np.clip((np.trace(diff, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)))
    out = {"frames": int(frames.size), "rotation_deg_median": float(np.median(angle)),
           "rotation_deg_max": float(angle.max()), "focal_pct": None}
    if other.get("focal_mm"):
        out["focal_pct"] = float(100.0 * (np.median(np.asarray(focal_mm)[frames]) / float(other["focal_mm"]) - 1.0))
    return out
