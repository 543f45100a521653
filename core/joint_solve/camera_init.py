"""A first camera rotation track from the planted foot, to start the joint solve.

A planted ankle is a static point, so between frames i and i+1 its viewing
ray turns exactly as the camera does.  The smallest rotation taking ray_i to
ray_{i+1} captures pan and tilt (roll and zoom are left to the solve, which
sees the whole body).  Increments are chained: ``R_{i+1} = Q_i R_i``.

Tried and not used: a bundle adjustment of a rotating, zooming camera on the footprints alone (each
stance spell's ankle a static direction; per-frame pan, tilt, roll and focal; robust camera speed,
smooth acceleration, a roll prior; 15 clips, 900 frames, 1 px).  Started from the *true* camera with
the true stance it drifts to 0.43 degrees on the built-in walk and 3.9 on jogging; from a still start
with the paper's stance it is worse than the paper's camera on the standard schedule (walk 0.53
against 0.22 degrees) and on rotation+zoom with no still spells (median of clips 4.1 against 3.2
degrees), and its zoom diverges there.  One footprint per frame gives two constraints for four camera
unknowns, and nothing ties one footprint to the next (on jogging 64 % of the frames have no planted
foot at all): only the body, through the stride, links them, which is the joint solve's job.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..nanstats import nanmedian
from ..skeleton import FEET, SEGMENTS
from .taylor import unit_rays


def rotations_from_stance(xy_filled: np.ndarray, stance: np.ndarray, focal_mm, image_size) -> np.ndarray:
    """(F, 3) rotation vectors (radians) of ``R_i`` from the stance foot's rays."""
    n = xy_filled.shape[0]
    feet = np.stack([xy_filled[:, FEET["l"]], xy_filled[:, FEET["r"]]], axis=1)  # (F, 2, 2)
    f = np.broadcast_to(np.asarray(focal_mm, dtype=float), (n,))
    rays = unit_rays(feet, f[:, None], image_size)                               # (F, 2, 3)
    side = np.clip(stance, 0, 1)
    a = rays[np.arange(n - 1), side[:-1]]
    b = rays[np.arange(1, n), side[:-1]]
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=-1)
    cos = np.sum(a * b, axis=-1)
    angle = np.arctan2(sin, cos)
    inc = axis / np.maximum(sin, 1e-12)[:, None] * angle[:, None]
    rots = [Rotation.identity()]
    for q in Rotation.from_rotvec(inc):
        rots.append(q * rots[-1])
    return np.stack([r.as_rotvec() for r in rots])


def figure_log_zoom(xy: np.ndarray, fps: float, smooth_s: float, focal_mm: float, image_size) -> np.ndarray:
    """(F,) log of how much larger than on frame 0 the figure's picture is: per frame the median over the
    bones of log(the angle between its two joints' viewing rays / the bone's median angle), frames without
    any bone filled from their neighbours, then a running median over half a second (a detector's slips)
    and a Gaussian of ``smooth_s``.  The rays are taken at ``focal_mm`` (frame 0's, or a guess).

    For a person standing on the spot this is the camera's zoom: angles between rays do not change when the
    camera turns (pixel lengths do: a figure panned to the picture's edge looks up to a tenth larger with
    a wide lens), a pose change moves a few bones' lengths but not their median, and the person does not
    come nearer.  For anyone else it is not (a step towards the camera grows the picture too)."""
    from scipy.ndimage import gaussian_filter1d, median_filter

    xy = np.asarray(xy, dtype=float)
    n = xy.shape[0]
    seg = np.array(SEGMENTS)
    rays = unit_rays(xy, focal_mm, image_size)
    cos = np.clip(np.sum(rays[:, seg[:, 0]] * rays[:, seg[:, 1]], axis=-1), -1.0, 1.0)
    length = np.arccos(cos)                                                     # (F, bones), NaN if lost
    seen = np.isfinite(length) & (length > 0)
    if n == 0 or not seen.any():
        return np.zeros(n)
    length = np.where(seen, length, np.nan)
    ratio = np.log(length / nanmedian(length, axis=0))           # NaN where the bone is not seen
    have = seen.any(axis=1)
    scale = np.full(n, np.nan)
    scale[have] = nanmedian(ratio[have], axis=1)
    frames = np.arange(n)
    scale = np.interp(frames, frames[have], scale[have])
    if fps and fps > 0 and n > 2:
        scale = median_filter(scale, size=max(3, int(round(0.5 * fps)) | 1), mode="nearest")
        if smooth_s > 0:
            scale = gaussian_filter1d(scale, smooth_s * fps, mode="nearest")
    return scale - scale[0]
