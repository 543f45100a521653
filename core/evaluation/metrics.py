"""Accuracy measures against synthetic truth, shared by every estimator and report.

Pure functions on numpy arrays (no I/O), so the evaluation command, the tests and
the benchmarks all score the same way.  Units are stated in every name:
``_pp`` percentage points, ``_pct`` percent, ``_deg`` degrees, ``_m`` metres.
"""

from __future__ import annotations

import numpy as np

from ..camera import rotation_matrix
from ..skeleton import CLASSES


def proportion_errors_pp(estimated: np.ndarray, actual: np.ndarray) -> dict:
    """Signed per-class error and mean / max absolute error, in percentage points."""
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(actual, dtype=float)
    err = (est / est.sum() - act / act.sum()) * 100.0
    return {"per_class": {c: float(e) for c, e in zip(CLASSES, err)},
            "mean_abs": float(np.mean(np.abs(err))), "max_abs": float(np.max(np.abs(err)))}


def frame_accuracy(estimated: np.ndarray, actual: np.ndarray) -> float:
    """Fraction of frames where two per-frame boolean labels agree."""
    e = np.asarray(estimated, dtype=bool)
    a = np.asarray(actual, dtype=bool)
    return float(np.mean(e == a)) if a.size else float("nan")


def _boundaries(moving: np.ndarray) -> np.ndarray:
    """Frames where the still/moving label changes (first frame of the new spell)."""
    m = np.asarray(moving, dtype=bool).astype(int)
    return np.flatnonzero(np.diff(m)) + 1


def spell_detection(estimated_moving: np.ndarray, actual_moving: np.ndarray, tolerance: int = 5) -> dict:
    """Camera-spell detection: frame-wise accuracy of ``camera_moving`` and boundary agreement.

    ``boundary_recall``: share of true still/moving boundaries with an estimated one
    within ``tolerance`` frames; ``boundary_precision``: the converse;
    ``boundary_offset_frames``: mean distance from each true boundary to the nearest estimated one.
    """
    tb = _boundaries(actual_moving)
    eb = _boundaries(estimated_moving)

    def near(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
        if src.size == 0:
            return np.zeros(0)
        if dst.size == 0:
            return np.full(src.size, np.inf)
        return np.min(np.abs(src[:, None] - dst[None, :]), axis=1)

    d_true = near(tb, eb)
    d_est = near(eb, tb)
    return {
        "frame_accuracy": frame_accuracy(estimated_moving, actual_moving),
        "boundary_recall": float(np.mean(d_true <= tolerance)) if tb.size else 1.0,
        "boundary_precision": float(np.mean(d_est <= tolerance)) if eb.size else (1.0 if not tb.size else 0.0),
        "boundary_offset_frames": float(np.mean(d_true)) if tb.size and np.isfinite(d_true).all() else
        (0.0 if not tb.size else float("inf")),
        "true_boundaries": int(tb.size), "estimated_boundaries": int(eb.size),
    }


def stance_accuracy(estimated: list, actual: list, clear: np.ndarray) -> float:
    """Share of frames where exactly one foot is planted (``clear``) whose stance foot is right."""
    clear = np.asarray(clear, dtype=bool)
    if not clear.any():
        return float("nan")
    hits = [estimated[i] == actual[i] for i in np.flatnonzero(clear)]
    return float(np.mean(hits))


def scale_error(estimated: np.ndarray, actual: np.ndarray) -> float:
    """Mean absolute relative error of the virtual scale parameter s' (a fraction, 0.01 = 1 %)."""
    e = np.asarray(estimated, dtype=float)
    a = np.asarray(actual, dtype=float)
    ok = np.isfinite(e) & np.isfinite(a) & (a != 0)
    return float(np.mean(np.abs(e[ok] / a[ok] - 1.0))) if ok.any() else float("nan")


def focal_error_pct(estimated_mm: float, actual_mm: float) -> float:
    """Relative error of frame 0's focal length, percent (signed)."""
    return float((estimated_mm / actual_mm - 1.0) * 100.0)


def zoom_focal_error_pct(estimated_mm: np.ndarray, actual_mm: np.ndarray, zoom_frames: np.ndarray) -> float:
    """Mean absolute per-frame focal error (percent) over the frames of zoom spells (NaN if none)."""
    z = np.asarray(zoom_frames, dtype=bool)
    if not z.any():
        return float("nan")
    e = np.asarray(estimated_mm, dtype=float)[z]
    a = np.asarray(actual_mm, dtype=float)[z]
    return float(np.mean(np.abs(e / a - 1.0)) * 100.0)


def rotation_errors_deg(estimated_rotvec_deg: np.ndarray, actual_rotvec_deg: np.ndarray) -> np.ndarray:
    """Per-frame angle (degrees) of the rotation taking the estimated camera rotation to the true one."""
    re = rotation_matrix(np.asarray(estimated_rotvec_deg, dtype=float))
    ra = rotation_matrix(np.asarray(actual_rotvec_deg, dtype=float))
    rel = np.einsum("fij,fkj->fik", re, ra)
    cos = np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return np.degrees(np.arccos(cos))


def rotation_error_deg(estimated_rotvec_deg: np.ndarray, actual_rotvec_deg: np.ndarray) -> float:
    """Median per-frame camera rotation error in degrees."""
    return float(np.median(rotation_errors_deg(estimated_rotvec_deg, actual_rotvec_deg)))


def similarity_align(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """``source`` points (N, 3) moved by the least-squares similarity (rotation, translation, scale) onto ``target``."""
    src = np.asarray(source, dtype=float)
    tgt = np.asarray(target, dtype=float)
    ok = np.isfinite(src).all(axis=1) & np.isfinite(tgt).all(axis=1)
    if ok.sum() < 3:
        return np.full_like(src, np.nan)
    mu_s, mu_t = src[ok].mean(axis=0), tgt[ok].mean(axis=0)
    a, b = src[ok] - mu_s, tgt[ok] - mu_t
    u, sig, vt = np.linalg.svd(b.T @ a)
    d = np.sign(np.linalg.det(u @ vt))
    fix = np.diag([1.0, 1.0, d])
    rot = u @ fix @ vt
    var = float((a * a).sum())
    scale = float((sig * np.diag(fix)).sum() / var) if var > 0 else 1.0
    return (src - mu_s) @ rot.T * scale + mu_t


def mpjpe_per_frame_m(estimated: np.ndarray, actual: np.ndarray) -> float:
    """Mean per-joint 3D error (metres) after a similarity alignment of every frame on its own."""
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(actual, dtype=float)
    errs = []
    for f in range(est.shape[0]):
        al = similarity_align(est[f], act[f])
        errs.append(np.linalg.norm(al - act[f], axis=-1))
    e = np.concatenate(errs)
    return float(np.nanmean(e))


def mpjpe_clip_m(estimated: np.ndarray, actual: np.ndarray) -> float:
    """Mean per-joint 3D error (metres) after one similarity alignment for the whole clip."""
    est = np.asarray(estimated, dtype=float).reshape(-1, 3)
    act = np.asarray(actual, dtype=float).reshape(-1, 3)
    al = similarity_align(est, act)
    return float(np.nanmean(np.linalg.norm(al - act, axis=-1)))


def followed_point_errors_px(found_xy: np.ndarray, true_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each followed point (``found_xy`` (F, K, 2), NaN where not followed) against the true point it starts
    on (the nearest of ``true_xy`` (F, S, 2) on its first frame): (K,) distance there and (K,) largest
    error of its motion since then, pixels. A tracker that sits on a feature beside the point (a patch's
    corner) has a start gap but no motion error; one that drifts or jumps has both."""
    found_xy = np.asarray(found_xy, dtype=float)
    true_xy = np.asarray(true_xy, dtype=float)
    k = found_xy.shape[1]
    gap, motion = np.full(k, np.nan), np.full(k, np.nan)
    for j in range(k):
        seen = np.flatnonzero(np.isfinite(found_xy[:, j, 0]))
        if seen.size == 0:
            continue
        f0 = seen[0]
        d = np.linalg.norm(true_xy[f0] - found_xy[f0, j], axis=-1)
        m = int(np.nanargmin(d))
        gap[j] = d[m]
        moved = found_xy[seen, j] - found_xy[f0, j]
        true_moved = true_xy[seen, m] - true_xy[f0, m]
        motion[j] = np.nanmax(np.linalg.norm(moved - true_moved, axis=-1))
    return gap, motion
