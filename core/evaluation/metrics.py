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


def similarity_align(source: np.ndarray, target: np.ndarray, scale: bool = True) -> np.ndarray:
    """``source`` points (N, 3) moved by the least-squares similarity (rotation, translation, scale) onto
    ``target``; ``scale=False``: rotation and translation alone (the source's own size kept)."""
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
    factor = float((sig * np.diag(fix)).sum() / var) if var > 0 and scale else 1.0
    return (src - mu_s) @ rot.T * factor + mu_t


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


# ---------------------------------------------------------------------------------------------------
# 3D motion: what an animator keys onto a rig (mirrored limbs, sliding planted feet, jitter)
# ---------------------------------------------------------------------------------------------------

def _limb_bones() -> tuple[tuple[int, int], ...]:
    from ..skeleton import LIMBS

    return tuple((chain[k], chain[k + 1]) for chain in LIMBS.values() for k in range(len(chain) - 1))


#: The eight limb bones a mirror shows on: upper arm, forearm, thigh and shin, left and right, as
#: (parent joint, child joint).
LIMB_BONES: tuple[tuple[int, int], ...] = _limb_bones()
#: A limb bone further than this from the truth's direction, after the frame's alignment, is mirrored.
MIRROR_ANGLE_DEG = 45.0


def limb_angles_deg(estimated: np.ndarray, actual: np.ndarray) -> np.ndarray:
    """(F, 8) angle in degrees between each estimated limb bone (:data:`LIMB_BONES`) and the truth's, after
    a similarity alignment of every frame on its own (NaN where the frame or the bone is not finite).

    A mirrored limb (depth flipped about the image plane) keeps its image and loses its direction: the
    frame's alignment cannot undo it, as the other bones pin the frame's rotation."""
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(actual, dtype=float)
    out = np.full((est.shape[0], len(LIMB_BONES)), np.nan)
    for f in range(est.shape[0]):
        al = similarity_align(est[f], act[f])
        for k, (p, c) in enumerate(LIMB_BONES):
            a, b = al[c] - al[p], act[f, c] - act[f, p]
            na, nb = np.linalg.norm(a), np.linalg.norm(b)
            if np.isfinite(na) and np.isfinite(nb) and na > 1e-9 and nb > 1e-9:
                out[f, k] = np.degrees(np.arccos(np.clip(a @ b / (na * nb), -1.0, 1.0)))
    return out


def mirrored_limb_frames(estimated: np.ndarray, actual: np.ndarray, max_angle_deg: float = MIRROR_ANGLE_DEG
                         ) -> np.ndarray:
    """(F,) True where any limb bone is more than ``max_angle_deg`` off the truth after the frame's
    alignment (:func:`limb_angles_deg`); a frame with no finite bone is False."""
    ang = limb_angles_deg(estimated, actual)
    return np.nan_to_num(ang, nan=0.0).max(axis=1) > max_angle_deg


def mirrored_limb_pct(estimated: np.ndarray, actual: np.ndarray, max_angle_deg: float = MIRROR_ANGLE_DEG) -> float:
    """Percent of frames with a mirrored limb (:func:`mirrored_limb_frames`)."""
    m = mirrored_limb_frames(estimated, actual, max_angle_deg)
    return float(100.0 * m.mean()) if m.size else float("nan")


#: A limb bone whose true depth across it is less than this share of its length lies nearly in the picture's
#: plane: its depth sign is not scored (:func:`depth_sign_error_pct`).
MIN_SLANT = 0.15


def depth_sign_error_pct(estimated: np.ndarray, actual: np.ndarray, estimated_rotvec_deg: np.ndarray,
                         actual_rotvec_deg: np.ndarray, min_slant: float = MIN_SLANT) -> np.ndarray:
    """(8,) per limb bone (:data:`LIMB_BONES`): percent of its frames, among those where the true bone's depth
    across it is more than ``min_slant`` of its length, where the estimated bone runs the other way in depth.

    Depths in each frame's camera axes (joints in frame-0 axes turned by the frame's camera rotation).
    Taylor's two candidates for a bone differ in exactly this sign; a wrong one on a shallow bone (about 17
    to 45 degrees off at ``min_slant`` 0.15) shows here and not as a mirrored limb.  NaN where a bone has no
    such frame."""
    def in_camera(joints, rotvec_deg):
        return np.einsum("fij,fkj->fki", rotation_matrix(np.asarray(rotvec_deg, dtype=float)),
                         np.asarray(joints, dtype=float))

    est, act = in_camera(estimated, estimated_rotvec_deg), in_camera(actual, actual_rotvec_deg)
    out = np.full(len(LIMB_BONES), np.nan)
    for k, (p, c) in enumerate(LIMB_BONES):
        true = act[:, c] - act[:, p]
        slant = true[:, 2] / np.maximum(np.linalg.norm(true, axis=-1), 1e-12)
        dz = est[:, c, 2] - est[:, p, 2]
        scored = (np.abs(slant) > min_slant) & np.isfinite(dz)
        if scored.any():
            out[k] = 100.0 * float(np.mean(np.sign(dz[scored]) != np.sign(slant[scored])))
    return out


def point_speeds(points: np.ndarray, fps: float) -> np.ndarray:
    """(F, ...) speed of points (F, ..., 3) in their units per second: central differences inside the clip,
    one-sided at its ends (NaN where a neighbour is missing)."""
    p = np.asarray(points, dtype=float)
    n = p.shape[0]
    v = np.full(p.shape, np.nan)
    if n < 2:
        return np.full(p.shape[:-1], np.nan)
    v[1:-1] = (p[2:] - p[:-2]) * (fps / 2.0)
    v[0] = (p[1] - p[0]) * fps
    v[-1] = (p[-1] - p[-2]) * fps
    return np.linalg.norm(v, axis=-1)


def planted_from_stance(stance: list, n_frames: int | None = None) -> np.ndarray:
    """(F, 2) bool (left, right ankle planted) from per-frame stance labels "l" / "r" / None (the truth's
    contact: on these frames that foot stands still on the floor)."""
    n = len(stance) if n_frames is None else n_frames
    out = np.zeros((n, 2), dtype=bool)
    for i, s in enumerate(stance[:n]):
        if s == "l":
            out[i, 0] = True
        elif s == "r":
            out[i, 1] = True
    return out


def planted_from_speed(actual: np.ndarray, fps: float, max_speed_m_s: float = 0.1) -> np.ndarray:
    """(F, 2) bool: the TRUE ankles (left, right) slower than ``max_speed_m_s`` (for truths without contacts)."""
    from ..skeleton import FEET

    act = np.asarray(actual, dtype=float)
    return point_speeds(act[:, [FEET["l"], FEET["r"]]], fps) < max_speed_m_s


def planted_foot_speed_mm_s(estimated: np.ndarray, actual: np.ndarray, fps: float, planted: np.ndarray) -> dict:
    """How fast the estimated ankles move while the true ones are planted, against the truth's own speed.

    ``estimated``/``actual`` (F, 17, 3) metres in one static set of axes (the frame-0 camera's: the
    solve's world); speeds are taken as they are, with no alignment (speed does not depend on rotation
    or translation, and both figures have the same stature: the estimate is scaled to the height it was
    given).  ``planted`` (F, 2) left/right.  Returns mean and median speeds (mm/s) of the estimate and of
    the truth over the planted ankle-frames, ``excess_mm_s`` = estimated mean - true mean, and ``n``."""
    from ..skeleton import FEET

    idx = [FEET["l"], FEET["r"]]
    se = point_speeds(np.asarray(estimated, dtype=float)[:, idx], fps) * 1000.0
    sa = point_speeds(np.asarray(actual, dtype=float)[:, idx], fps) * 1000.0
    sel = np.asarray(planted, dtype=bool) & np.isfinite(se) & np.isfinite(sa)
    if not sel.any():
        nan = float("nan")
        return {"estimated_mm_s": nan, "true_mm_s": nan, "estimated_median_mm_s": nan, "true_median_mm_s": nan,
                "excess_mm_s": nan, "n": 0}
    e, a = se[sel], sa[sel]
    return {"estimated_mm_s": float(e.mean()), "true_mm_s": float(a.mean()),
            "estimated_median_mm_s": float(np.median(e)), "true_median_mm_s": float(np.median(a)),
            "excess_mm_s": float(e.mean() - a.mean()), "n": int(sel.sum())}


def _aligned(estimated: np.ndarray, actual: np.ndarray, align: str) -> np.ndarray:
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(actual, dtype=float)
    if align in ("clip", "clip-rigid"):
        return similarity_align(est.reshape(-1, 3), act.reshape(-1, 3), scale=align == "clip").reshape(est.shape)
    if align == "frame":
        return np.stack([similarity_align(est[f], act[f]) for f in range(est.shape[0])])
    raise ValueError(f"align must be 'clip', 'clip-rigid' or 'frame', got {align!r}")


def acceleration_error_mm_s2(estimated: np.ndarray, actual: np.ndarray, fps: float, align: str = "clip") -> float:
    """Jitter: mean over joints and inner frames of ``|a_est - a_true|`` (mm/s^2), accelerations by second
    differences, after aligning the estimate on the truth.

    ``align="clip"``: one similarity for the whole clip, so the figure's path in the world counts (a
    shaking root shows); ``"clip-rigid"``: the same without its scale, for estimates whose size the stature
    given fixes (a similarity shrinks an estimate placed too far, by a lens too long, and its jitter with
    it); ``"frame"``: every frame on its own, the pose's own jitter alone."""
    est = _aligned(estimated, actual, align)
    act = np.asarray(actual, dtype=float)
    if est.shape[0] < 3:
        return float("nan")
    acc_e = (est[2:] - 2.0 * est[1:-1] + est[:-2]) * fps * fps
    acc_a = (act[2:] - 2.0 * act[1:-1] + act[:-2]) * fps * fps
    err = np.linalg.norm(acc_e - acc_a, axis=-1)
    return float(np.nanmean(err) * 1000.0) if np.isfinite(err).any() else float("nan")


def mpjpe_frames_m(estimated: np.ndarray, actual: np.ndarray) -> np.ndarray:
    """(F,) mean per-joint error (metres) of each frame after its own similarity alignment (the per-frame
    P-MPJPE that :func:`mpjpe_per_frame_m` averages)."""
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(actual, dtype=float)
    out = np.full(est.shape[0], np.nan)
    for f in range(est.shape[0]):
        e = np.linalg.norm(similarity_align(est[f], act[f]) - act[f], axis=-1)
        if np.isfinite(e).any():
            out[f] = np.nanmean(e)
    return out
