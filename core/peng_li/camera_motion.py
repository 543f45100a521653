"""Step 4a (paper 3.3): the camera motion of a moving spell, from the stance foot.

A planted foot is a static scene point, so its image moves only because the camera
does.  One point fixes two parameters per frame: the pan and tilt of a
"directional rotating" camera, or (radially) the focal length of a "zooming" one.
For each model the stance sequence that makes the camera smoothest is found by
:func:`core.peng_li.stance.stance_dp`; the model whose best sequence is smoother
(including, for zooming, how far the foot moves off its radial line, which no
zoom can explain) is chosen, as in the paper.

Camera convention (:mod:`core.camera`): ``X_i = R_i X_0`` with
``R_i = pan_tilt_roll_matrix(pan_i, tilt_i)`` (absolute angles, no roll), and
film point = ``f_i * X_i[:2] / X_i[2]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import pan_tilt_roll_matrix
from .foot_drift import without_drift
from .stance import fill_unknown, stance_dp


@dataclass
class SpellCamera:
    model: str                 # "rotate" or "zoom"
    stance: np.ndarray         # (n,) 0 = left, 1 = right
    pan_deg: np.ndarray        # (n,) absolute
    tilt_deg: np.ndarray       # (n,) absolute
    focal_mm: np.ndarray       # (n,)
    cost: float                # smoothness cost per frame (mm^2), lower is smoother
    kind: str = "moving"


def rotation_increments(feet: np.ndarray, focal_mm: float) -> np.ndarray:
    """Frame-to-frame change of each foot's viewing direction (F, 2, 2), as film mm at the focal length.

    Azimuth about the camera y axis and elevation above the camera xz plane are
    exactly what a pan and (for small pans) a tilt change.
    """
    x, y = feet[..., 0], feet[..., 1]
    az = np.arctan2(x, focal_mm)
    el = np.arctan2(y, np.hypot(x, focal_mm))
    ang = np.stack([az, el], axis=-1) * focal_mm
    out = np.full_like(ang, np.nan)
    out[1:] = np.diff(ang, axis=0)
    return out


def zoom_increments(feet: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Radial increments (F, 2, 1) in mm (r * d log r) and the squared tangential misfit (F, 2)."""
    r = np.linalg.norm(feet, axis=-1)
    out = np.full(feet.shape[:-1] + (1,), np.nan)
    out[1:, :, 0] = np.diff(np.log(np.maximum(r, 1e-9)), axis=0) * r[1:]
    misfit = np.zeros(feet.shape[:-1])
    prev, cur = feet[:-1], feet[1:]
    cross = prev[..., 0] * cur[..., 1] - prev[..., 1] * cur[..., 0]
    misfit[1:] = (cross / np.maximum(r[:-1], 1e-9)) ** 2
    return out, np.where(np.isfinite(misfit), misfit, np.nan)


def smoothness_pairwise(incr: np.ndarray) -> np.ndarray:
    """pairwise[i, a, b] = |incr[i, b] - incr[i-1, a]|^2: the change of camera increment.

    The paper measures smoothness by the standard deviation of the motion
    parameters between neighbouring frames; summing squared changes of the
    increment is that spread measured locally, so a camera that speeds up and
    slows down smoothly is still smooth, and it splits into neighbouring-frame
    terms for the dynamic programme.  Unknown terms get a high (90th percentile) cost.
    """
    n = incr.shape[0]
    pw = np.zeros((n, 2, 2))
    if n > 2:
        d = incr[2:, None, :, :] - incr[1:-1, :, None, :]     # (n-2, a, b, dim)
        pw[2:] = np.sum(d * d, axis=-1)
    return fill_unknown(pw)


def solve_pan_tilt(w: np.ndarray, v: np.ndarray, tilt_prev_deg: float) -> tuple[float, float]:
    """Absolute (pan, tilt) in degrees with ``pan_tilt_roll_matrix(pan, tilt) @ w`` along ``v``.

    ``w`` is the point's direction in frame-0 camera axes, ``v`` its viewing ray
    in the current frame.  With ``R = Q^T``, ``Q = Ry(pan) Rx(-tilt)``: the tilt
    makes ``Rx(-tilt) v`` as high as ``w`` (a pan keeps heights), the pan then
    matches the azimuth.  Of the two tilts the one nearer ``tilt_prev_deg`` wins.
    """
    w = w / np.linalg.norm(w)
    v = v / np.linalg.norm(v)
    a = np.hypot(v[1], v[2])
    phi = np.arctan2(v[2], v[1])
    c = np.clip(w[1] / max(a, 1e-12), -1.0, 1.0)
    cands = [phi + np.arccos(c), phi - np.arccos(c)]
    prev = np.radians(tilt_prev_deg)
    t = min(cands, key=lambda tt: abs(np.angle(np.exp(1j * (tt - prev)))))
    t = prev + np.angle(np.exp(1j * (t - prev)))
    ct, st = np.cos(-t), np.sin(-t)
    u = np.array([v[0], v[1] * ct - v[2] * st, v[1] * st + v[2] * ct])
    pan = np.arctan2(w[0], w[2]) - np.arctan2(u[0], u[2])
    pan = np.angle(np.exp(1j * pan))
    return float(np.degrees(pan)), float(np.degrees(t))


def _ray(p: np.ndarray, f: float) -> np.ndarray:
    return np.array([p[0], p[1], f])


def track_rotation(feet: np.ndarray, stance: np.ndarray, focal_mm: float, pan0: float, tilt0: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Absolute pan/tilt per frame of a spell, from the stance foot, starting at (pan0, tilt0).

    The foot's world direction is anchored when it becomes the stance foot and
    kept for the whole run, so noise does not accumulate frame by frame.
    """
    n = feet.shape[0]
    pan = np.full(n, pan0, dtype=float)
    tilt = np.full(n, tilt0, dtype=float)
    anchor = None
    for i in range(n):
        s = stance[i]
        p = feet[i, s]
        if i > 0:
            pan[i], tilt[i] = pan[i - 1], tilt[i - 1]
        if i > 0 and (anchor is None or s != stance[i - 1]):
            anchor = None
            q = feet[i - 1, s]
            if np.all(np.isfinite(q)):
                r_prev = pan_tilt_roll_matrix(pan[i - 1], tilt[i - 1])
                anchor = r_prev.T @ _ray(q, focal_mm)
        if anchor is None and i == 0 and np.all(np.isfinite(p)):
            anchor = pan_tilt_roll_matrix(pan0, tilt0).T @ _ray(p, focal_mm)
            continue
        if i > 0 and anchor is not None and np.all(np.isfinite(p)):
            pan[i], tilt[i] = solve_pan_tilt(anchor, _ray(p, focal_mm), tilt[i - 1])
    return pan, tilt


def track_zoom(feet: np.ndarray, stance: np.ndarray, focal0: float) -> np.ndarray:
    """Focal length per frame of a zooming spell: the stance foot scales about the centre."""
    n = feet.shape[0]
    f = np.full(n, focal0, dtype=float)
    anchor, f_anchor = None, focal0
    for i in range(n):
        s = stance[i]
        if i > 0:
            f[i] = f[i - 1]
        if i == 0 or s != stance[i - 1] or anchor is None:
            src = feet[i - 1, s] if i > 0 else feet[i, s]
            anchor = src if np.all(np.isfinite(src)) else None
            f_anchor = f[i - 1] if i > 0 else focal0
        p = feet[i, s]
        if i > 0 and anchor is not None and np.all(np.isfinite(p)):
            denom = float(anchor @ anchor)
            if denom > 1e-9:
                f[i] = f_anchor * float(p @ anchor) / denom
    return f


def estimate_spell_models(feet: np.ndarray, focal_mm: float, pan0: float, tilt0: float, min_run: int,
                          models=("rotate", "zoom"), drift: np.ndarray | None = None,
                          body_cue: np.ndarray | None = None) -> list[SpellCamera]:
    """The smoothest camera motion of each model for one spell's feet (n, 2, 2) film mm.

    ``drift`` (2,), film mm per frame: the planted ankle's own creep, taken out of the feet the
    rotating model reads; the zooming model keeps the raw feet (:mod:`.foot_drift` says why).
    ``body_cue`` (n, 2): an extra stance cost per frame and foot, added to every model's stance choice
    but not to the smoothness cost that compares the models.
    """
    n = feet.shape[0]
    results = []
    for model in models:
        if model == "rotate":
            feet_rot = feet if drift is None else without_drift(feet, drift)
            incr = rotation_increments(feet_rot, focal_mm)
            unary = np.zeros((n, 2))
        elif model == "zoom":
            incr, unary = zoom_increments(feet)
            unary = fill_unknown(unary)
        else:
            raise ValueError(f"unknown camera motion model {model!r}")
        pairwise = smoothness_pairwise(incr)
        stance = stance_dp(unary if body_cue is None else unary + body_cue, pairwise, min_run)
        cost = float(unary[np.arange(n), stance].sum() + pairwise[np.arange(1, n), stance[:-1], stance[1:]].sum())
        cost /= max(1, n - 2)
        if model == "rotate":
            pan, tilt = track_rotation(feet_rot, stance, focal_mm, pan0, tilt0)
            focal = np.full(n, focal_mm)
            dp, dt = abs(pan[-1] - pan[0]), abs(tilt[-1] - tilt[0])
            kind = "pan" if dt < 0.3 * dp else ("tilt" if dp < 0.3 * dt else "pan_tilt")
        else:
            focal = track_zoom(feet, stance, focal_mm)
            pan, tilt = np.full(n, pan0), np.full(n, tilt0)
            kind = "zoom"
        results.append(SpellCamera(model, stance, pan, tilt, focal, cost, kind))
    return results


def estimate_spell(feet: np.ndarray, focal_mm: float, pan0: float, tilt0: float, min_run: int,
                   models=("rotate", "zoom")) -> SpellCamera:
    """The model whose best stance sequence gives the smoothest camera (smoothness alone)."""
    return min(estimate_spell_models(feet, focal_mm, pan0, tilt0, min_run, models), key=lambda r: r.cost)


#: Joints whose image distance measures the figure's size: pelvis to neck, a nearly rigid,
#: nearly upright chain that no limb swing foreshortens much.
SIZE_CHAIN = (0, 3)


def size_roughness(points_static: np.ndarray) -> float:
    """How much the undone figure grows or shrinks beyond a smooth trend (RMS of log size).

    The paper: undoing the wrong camera motion leaves "significant enlargement /
    shrinking effects" in the data.  A person's own approach is smooth over a
    couple of seconds, so a quadratic trend absorbs it; a zoom left in the data
    is an S-shaped step that the trend cannot follow.
    """
    a, b = SIZE_CHAIN
    size = np.linalg.norm(points_static[:, b] - points_static[:, a], axis=-1)
    ok = np.isfinite(size) & (size > 0)
    if ok.sum() < 5:
        return float("nan")
    t = np.flatnonzero(ok).astype(float)
    y = np.log(size[ok])
    coef = np.polyfit(t, y, 2)
    return float(np.sqrt(np.mean((y - np.polyval(coef, t)) ** 2)))
