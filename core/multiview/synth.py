"""Several static cameras filming one motion: the test and benchmark data of the multi-view path.

The cameras stand on a ring around where the person moves, at a random height of about a standing
eye level, each looking at the middle of the motion, with its own lens; each view gets its own noise
(and, optionally, a detector's errors, :mod:`core.synthetic.footage_sim.detector`).  Joints behind the camera or
outside the picture are missing, as a real detector would report them.
"""

from __future__ import annotations

import numpy as np

from ..synthetic.footage_sim.detector import DetectorErrors, apply_detector_errors
from ..synthetic.motion import Motion
from ..tracks import Tracks
from .cameras import ViewCamera, look_at


def ring_cameras(motion: Motion, n_views: int = 3, *, radius_m: float = 4.5, image_size=(1280.0, 720.0),
                 focal_mm=(24.0, 50.0), gap_deg=(60.0, 150.0), seed: int = 0) -> list[ViewCamera]:
    """``n_views`` cameras spread round the motion (random gaps of ``gap_deg`` between neighbours),
    lenses drawn from ``focal_mm`` (36 mm film), each looking at the motion's middle."""
    from ..camera import mm_per_pixel

    rng = np.random.default_rng(seed)
    joints = np.asarray(motion.joints, dtype=float)
    middle = np.nanmean(joints.reshape(-1, 3), axis=0)
    spread = float(np.nanmax(np.linalg.norm(joints[:, 0, [0, 2]] - middle[[0, 2]], axis=-1)))
    start = rng.uniform(0, 2 * np.pi)
    angles = start + np.cumsum(np.r_[0.0, rng.uniform(np.radians(gap_deg[0]), np.radians(gap_deg[1]), n_views - 1)])
    cams = []
    for k, a in enumerate(angles):
        r = radius_m + spread
        pos = middle + np.array([r * np.cos(a), 0.0, r * np.sin(a)])
        pos[1] = rng.uniform(1.0, 1.8)
        f_mm = float(np.exp(rng.uniform(np.log(focal_mm[0]), np.log(focal_mm[1]))))
        cams.append(ViewCamera(name=f"view {k + 1}", image_size=tuple(image_size),
                               focal_px=f_mm / mm_per_pixel(image_size), rotation=look_at(pos, middle),
                               position=pos))
    return cams


def film_views(motion: Motion, cameras: list[ViewCamera], *, noise_px: float = 1.0,
               detector: DetectorErrors | None = None, seed: int = 0) -> list[Tracks]:
    """One tracks object per camera, frame-synchronous."""
    out = []
    for k, cam in enumerate(cameras):
        uv = cam.project(motion.joints)                                  # (F, 17, 2)
        w, h = cam.image_size
        visible = np.isfinite(uv).all(axis=-1) & (uv[..., 0] >= 0) & (uv[..., 0] < w) & (uv[..., 1] >= 0) \
            & (uv[..., 1] < h)
        uv = np.where(np.isfinite(uv), uv, 0.0)
        xy, conf, _ = apply_detector_errors(uv, visible, noise_px, motion.fps, (w, h), detector or DetectorErrors(),
                                            seed * 101 + k)
        out.append(Tracks(xy=xy, conf=conf, fps=motion.fps, image_size=(w, h), source=f"{motion.name} / {cam.name}",
                          meta={"camera": cam.name}))
    return out


def steady_repeat(motion: Motion, n_frames: int, *, start: int = 0,
                  max_gap_m: float = 0.05) -> tuple[Motion, int] | None:
    """A perfectly steady version of a periodic motion: its cycle from frame ``start`` repeated
    ``n_frames`` long, moved on by the cycle's horizontal travel each time, and the cycle in frames.

    The cycle is the lag of 0.6-1.6 s at which the pose (relative to the pelvis) comes back closest; None
    when it does not come back within ``max_gap_m`` on average (not a repeated movement).  The hardest
    case for synchronisation: a cycle later the figure stands in exactly the same pose, moved along."""
    joints = np.asarray(motion.joints, dtype=float)[start:]
    rel = joints - joints[:, :1]
    lags = range(max(2, int(0.6 * motion.fps)), int(1.6 * motion.fps) + 1)
    window = int(0.5 * motion.fps)
    gaps = {p: float(np.nanmean(np.linalg.norm(rel[p:p + window] - rel[:window], axis=-1)))
            for p in lags if p + window <= len(rel)}
    if not gaps:
        return None
    period = min(gaps, key=gaps.get)
    if gaps[period] > max_gap_m:
        return None
    travel = joints[period, 0] - joints[0, 0]
    travel[1] = 0.0
    t = np.arange(n_frames)
    out = joints[t % period] + (t // period)[:, None, None] * travel
    contacts = np.asarray(motion.contacts)[start:][t % period]
    return Motion(f"{motion.name} (steady)", motion.fps, out, motion.class_lengths, contacts), period
