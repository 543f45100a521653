"""Step 5 (paper 4.1): the virtual scale parameter s'_i = d_1 / d_i of every frame.

Each frame is read as a virtual figure whose root (pelvis) lies on the image
plane, i.e. the real figure scaled by f / d_i.  To compare frames, the relative
root distance d_i is needed.  A planted foot does not move, so during one stance
run its depth is fixed; the longest projection of that leg's calf in the run is
taken as the moment the calf is parallel to the image plane, so the run's foot
depth is proportional to 1 / (longest calf projection) (both calves are equally
long).  When the stance swaps, the pelvis lies roughly in the vertical plane
through both feet: the image's vertical line through the pelvis meets the segment
between the two feet at a point whose depth (inverse depth is linear along an
image line) is the pelvis depth.  Between swaps the depth is interpolated
linearly; before the first and after the last swap it follows the trend of the
nearest two swaps (``extrapolate=False`` holds it, the literal reading).
"""

from __future__ import annotations

import numpy as np

from ..runs import runs as _runs
from ..skeleton import FEET, JOINT_INDEX, KNEES

PELVIS = JOINT_INDEX["pelvis"]
_ANKLE = (FEET["l"], FEET["r"])
_KNEE = (KNEES["l"], KNEES["r"])


def stance_runs(stance: np.ndarray, min_len: int) -> list[tuple[int, int, int]]:
    """(foot, start, end_exclusive) of stance runs at least ``min_len`` frames long (stance -1 = unknown)."""
    out = []
    for foot in (0, 1):
        for a, b in _runs(stance == foot):
            if b - a >= min_len:
                out.append((foot, int(a), int(b)))
    return sorted(out, key=lambda r: r[1])


def swap_depths(points: np.ndarray, stance: np.ndarray, min_len: int) -> tuple[np.ndarray, np.ndarray]:
    """Frames of stance swaps and the relative pelvis depth there (arbitrary common unit)."""
    runs = stance_runs(stance, min_len)
    calf = np.linalg.norm(points[:, list(_KNEE)] - points[:, list(_ANKLE)], axis=-1)   # (F, 2)
    depth_of_run = []
    for foot, a, b in runs:
        seg = calf[a:b, foot]
        longest = np.nanmax(seg) if np.isfinite(seg).any() else np.nan
        depth_of_run.append(1.0 / longest if longest > 0 else np.nan)
    frames, depths = [], []
    for k in range(len(runs) - 1):
        (fa, _, _), (fb, b0, _) = runs[k], runs[k + 1]
        da, db = depth_of_run[k], depth_of_run[k + 1]
        if fa == fb or not (np.isfinite(da) and np.isfinite(db)):
            continue
        i = b0
        pa, pb, pel = points[i, _ANKLE[fa]], points[i, _ANKLE[fb]], points[i, PELVIS]
        if not (np.isfinite(pa).all() and np.isfinite(pb).all() and np.isfinite(pel).all()):
            continue
        dx = pb[0] - pa[0]
        t = 0.5 if abs(dx) < 1e-6 else float(np.clip((pel[0] - pa[0]) / dx, 0.0, 1.0))
        frames.append(i)
        depths.append(1.0 / ((1.0 - t) / da + t / db))
    return np.asarray(frames, dtype=int), np.asarray(depths, dtype=float)


def virtual_scale(points: np.ndarray, stance: np.ndarray, min_len: int, extrapolate: bool = True
                  ) -> tuple[np.ndarray, dict]:
    """s'_i (F,) with s'_0 = 1 from still-camera film points (F, 17, 2) and stance (F,) in {-1, 0, 1}."""
    n = points.shape[0]
    frames, depths = swap_depths(points, np.asarray(stance), min_len)
    info = {"swap_frames": frames.tolist()}
    if frames.size == 0:
        info["warning"] = "no stance swap found: virtual scale held at 1"
        return np.ones(n), info
    t = np.arange(n)
    d = np.interp(t, frames, depths)
    if extrapolate and frames.size >= 2:
        # Continue the trend of the nearest two swaps beyond the first and last swap (a walk's
        # depth changes steadily), but never through zero.
        for sl, (i0, i1) in ((t < frames[0], (0, 1)), (t > frames[-1], (-2, -1))):
            slope = (depths[i1] - depths[i0]) / max(1, frames[i1] - frames[i0])
            ref = frames[i0] if i0 == 0 else frames[i1]
            dref = depths[i0] if i0 == 0 else depths[i1]
            d[sl] = np.maximum(dref + slope * (t[sl] - ref), 0.25 * dref)
    return d[0] / d, info
