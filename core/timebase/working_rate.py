"""Decimate tracks to the working rate and bring an estimate back to the input's frames."""

from __future__ import annotations

import copy

import numpy as np

from ..result import Estimate, FrameEstimate
from ..skeleton import N_JOINTS, PARENTS
from ..tracks import StaticTracks, Tracks
from .frames import frames_between

#: The rate the estimators were designed and measured at.
WORKING_FPS = 30.0
#: Keep at least this many working frames (short clips are not decimated below it).
MIN_WORKING_FRAMES = 60


def decimation_factor(fps: float, n_frames: int) -> int:
    """How many input frames make one working frame (1: none)."""
    k = max(1, int(round(fps / WORKING_FPS)))
    while k > 1 and n_frames // k < MIN_WORKING_FRAMES:
        k -= 1
    return k


def _window(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and weights of the average that makes a working frame: one frame interval of the
    working rate centred on the frame itself (an even ``k`` gives its two end frames half weight)."""
    half = k // 2
    offsets = np.arange(-half, half + 1)
    weights = np.ones(offsets.size)
    if k % 2 == 0:
        weights[[0, -1]] = 0.5
    return offsets, weights


def to_working_rate(tracks: Tracks, k: int) -> Tracks:
    """Working frame i is input frame i*k averaged over one working interval (NaN-aware), so its time
    is the time a camera at the working rate would have filmed.  Static scene tracks go the same way."""
    if k <= 1:
        return tracks
    xy, conf = _average(tracks.xy, tracks.conf, k)
    static = tracks.static
    if static is not None:
        static = StaticTracks(static.names, *_average(static.xy, static.conf, k))
    pts = tracks.landmarks_3d
    if pts is not None:   # the detector's 3D joints go the same way
        pts = _average(pts, np.isfinite(pts).all(axis=-1).astype(float), k)[0]
    meta = dict(tracks.meta)
    meta["decimated_from_fps"] = tracks.fps
    return tracks.replaced(xy=xy, conf=conf, fps=tracks.fps / k, meta=meta, static=static, landmarks_3d=pts)


def _average(xy: np.ndarray, conf: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (F, P, 2 or 3) and confidence (F, P) averaged to every k-th frame (see :func:`to_working_rate`)."""
    n = xy.shape[0]
    centres = np.arange(0, n, k)
    offsets, weights = _window(k)
    idx = centres[:, None] + offsets[None]
    inside = (idx >= 0) & (idx < n)
    idx = np.clip(idx, 0, n - 1)
    xy = xy[idx]                                             # (m, W, P, 2)
    conf = conf[idx]
    wgt = np.where(inside[..., None] & (conf > 0), weights[None, :, None], 0.0)   # (m, W, P)
    total = wgt.sum(axis=1)
    mean = np.einsum("mwj,mwjc->mjc", wgt, np.where(np.isfinite(xy), xy, 0.0))
    out = np.where(total[..., None] > 0, mean / np.maximum(total, 1e-12)[..., None], np.nan)
    c = np.where(total > 0, np.einsum("mwj,mwj->mj", wgt, conf) / np.maximum(total, 1e-12), 0.0)
    return out, c


def _positions(n_full: int, k: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For every input frame: the working frames before/after it and the weight of the one after."""
    return frames_between(np.arange(n_full) / k, 0.0, m - 1)   # working frame i is input frame i*k


def _joints_between(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Poses between ``a`` and ``b`` (both (F, 17, 3)) at weights ``w`` (F,): the root moves linearly,
    each bone turns at ``a``'s length."""
    out = np.empty_like(a)
    w = w[:, None]
    out[:, 0] = (1 - w) * a[:, 0] + w * b[:, 0]
    for j in range(1, N_JOINTS):                          # parents precede children
        p = PARENTS[j]
        da, db = a[:, j] - a[:, p], b[:, j] - b[:, p]
        length = np.linalg.norm(da, axis=-1, keepdims=True)
        d = (1 - w) * da + w * db
        nd = np.linalg.norm(d, axis=-1, keepdims=True)
        turned = d * (length / np.where(nd > 1e-12, nd, 1.0))
        out[:, j] = out[:, p] + np.where(nd > 1e-12, turned, da)
    return out


def to_full_rate(est: Estimate, k: int, n_full: int) -> Estimate:
    """``est`` (made on working frames) with one frame per input frame, and its frame indices scaled."""
    if k <= 1:
        return est
    m = len(est.frames)
    i0, i1, w = _positions(n_full, k, m)
    nearest = np.where(w < 0.5, i0, i1)
    wc = w[:, None]
    rv = np.array([f.rotvec_deg for f in est.frames], dtype=float)
    rv = (1 - wc) * rv[i0] + wc * rv[i1]
    log_f = np.log(np.array([f.focal_mm for f in est.frames], dtype=float))
    focal = np.exp((1 - w) * log_f[i0] + w * log_f[i1])
    scale = np.array([f.scale for f in est.frames], dtype=float)
    scale = (1 - w) * scale[i0] + w * scale[i1]
    joints = None
    if all(f.joints_3d is not None for f in est.frames):
        j3 = np.array([f.joints_3d for f in est.frames], dtype=float)
        joints = _joints_between(j3[i0], j3[i1], w).tolist()
    frames = []
    for f in range(n_full):
        src = est.frames[int(nearest[f])]
        frames.append(FrameEstimate(
            stance=src.stance, camera_moving=src.camera_moving,
            rotvec_deg=tuple(float(v) for v in rv[f]), focal_mm=float(focal[f]), scale=float(scale[f]),
            joints_3d=None if joints is None else joints[f], reprojection_px=None))
    diag = copy.deepcopy(est.diagnostics)
    spells = diag.get("spells") or []
    for sp in spells:
        sp["start"] = max(0, int(sp["start"]) * k - k // 2)
        sp["end"] = min(n_full - 1, int(sp["end"]) * k + (k - 1) // 2)
    if spells:
        spells[-1]["end"] = n_full - 1
    if "swap_frames" in diag:
        diag["swap_frames"] = [int(v) * k for v in diag["swap_frames"]]
    diag["working_rate"] = {"factor": int(k), "frames": int(m)}
    return Estimate(method=est.method, proportions=dict(est.proportions), focal_mm=est.focal_mm, frames=frames,
                    height_m=est.height_m, diagnostics=diag)
