"""Rotation-only bundle adjustment: per-frame rotation and focal length, and one direction per static point.

A camera that turns and zooms about a fixed centre sees a static point with direction ``d``
(unit, frame-0 axes) at ``f_i * (R_i d)_xy / (R_i d)_z`` (pixels from the image centre):
Hartley's and de Agapito, Hayman and Reid's model of a rotating camera with varying focal length
(square pixels, principal point at the centre).  Maximising the likelihood of every tracked point
over ``R_i``, ``g_i = log f_i`` and ``d`` is this least-squares problem; the focal length is
determined by it once the camera turns enough (:mod:`.determinacy`).

A camera carried by hand rolls little and smoothly, so consecutive frames are tied by a prior on
the second difference of the roll (:data:`ROLL_ACCEL_DEG`): one frame's dozen points fix its pan and
tilt well but its roll poorly (the points' spread in the picture is its lever), and the neighbours
lend it theirs.  The same prior on pan, tilt and log focal length (:data:`ROT_ACCEL_DEG`,
:data:`FOCAL_ACCEL`) is there and off: measured, it traded the focal length for little rotation
(``docs/scene_camera.md``).

Levenberg-Marquardt on the normal equations, the cameras (4 unknowns each, a band in time)
eliminated into a Schur complement over the points (2 unknowns each): a clip of 900 frames and
16 points is a banded solve with 32 right-hand sides and a 32 x 32 system per step.  Huber
weights (IRLS) keep a slipping track from pulling the camera.  The reference frame's rotation is
held (the gauge).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solveh_banded

from ..camera import rotvec_deg
from ..joint_solve.solver import rot_and_left_jacobian, skew
from ..nanstats import RAYLEIGH_MEDIAN

#: Prior sigma of the camera's angular acceleration (degrees per frame^2) and of the log focal length's
#: second difference, between consecutive frames of the adjusted stretch (None: no prior).
ROT_ACCEL_DEG: float | None = None
ROLL_ACCEL_DEG: float | None = 0.02
FOCAL_ACCEL: float | None = None
#: Band half-width of the camera block: second differences reach two frames of 4 unknowns.
_U = 11
#: Huber threshold, in robust standard deviations of the residuals.
HUBER_K = 2.5
#: Assumed noise (px) until the residuals give their own scale.
START_SIGMA_PX = 1.0


@dataclass
class Observations:
    """Tracked static points: ``frame`` and ``point`` indices (m,), ``uv`` (m, 2) pixels from the centre."""

    frame: np.ndarray
    point: np.ndarray
    uv: np.ndarray
    n_frames: int
    n_points: int
    times: np.ndarray | None = None    # (n_frames,) clip frame numbers: which adjusted frames are consecutive


@dataclass
class BundleState:
    R: np.ndarray          # (F, 3, 3): frame-0 axes -> frame i's camera axes
    g: np.ndarray          # (F,) log focal length in pixels
    d: np.ndarray          # (S, 3) unit directions in frame-0 axes


@dataclass
class BundleResult:
    state: BundleState
    residuals: np.ndarray  # (m, 2) pixels
    sigma_px: float        # robust standard deviation of the residuals
    inlier: np.ndarray     # (m,) bool: within the Huber threshold
    cov_g_ref: float       # variance of log f at the reference frame (from the prior-free information)
    cost: float
    iterations: int


def tangent_basis(d: np.ndarray) -> np.ndarray:
    """(S, 3, 2): two unit vectors orthogonal to each direction ``d`` and to each other."""
    a = np.where(np.abs(d[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    b1 = a - np.sum(a * d, axis=1, keepdims=True) * d
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    b2 = np.cross(d, b1)
    return np.stack([b1, b2], axis=-1)


def project(state: BundleState, obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """Camera-axis points (m, 3) and their projections (m, 2) in pixels from the centre."""
    Y = np.einsum("mab,mb->ma", state.R[obs.frame], state.d[obs.point])
    z = np.where(np.abs(Y[:, 2]) < 1e-9, 1e-9, Y[:, 2])
    return Y, np.exp(state.g[obs.frame])[:, None] * Y[:, :2] / z[:, None]


def _cost(e: np.ndarray, sigma: float, prior) -> float:
    en = np.linalg.norm(e, axis=1) / sigma
    k = HUBER_K
    c = float(np.sum(np.where(en <= k, 0.5 * en ** 2, k * en - 0.5 * k * k)))
    return c + prior


def _triples(obs: Observations) -> np.ndarray:
    """Middle indices i of adjusted frames i-1, i, i+1 that are consecutive clip frames."""
    t = np.arange(obs.n_frames) if obs.times is None else np.asarray(obs.times)
    if t.size < 3:
        return np.zeros(0, dtype=int)
    return np.flatnonzero((t[1:-1] - t[:-2] == 1) & (t[2:] - t[1:-1] == 1)) + 1


def _second_differences(st: BundleState, mid: np.ndarray) -> np.ndarray:
    """(k, 4) raw second differences at frames ``mid``: rotation (radians; the change of the angular
    velocity in camera axes) and log focal length."""
    v_next = np.radians(rotvec_deg(st.R[mid + 1] @ np.transpose(st.R[mid], (0, 2, 1))))
    v_prev = np.radians(rotvec_deg(st.R[mid] @ np.transpose(st.R[mid - 1], (0, 2, 1))))
    g = st.g
    return np.concatenate([v_next - v_prev, (g[mid + 1] - 2 * g[mid] + g[mid - 1])[:, None]], axis=1)


def _sigmas() -> np.ndarray:
    """(4,) sigmas of the second differences (radians, log focal); infinite where a prior is off."""
    return np.concatenate([np.radians(_rot_sigmas()), [_focal_sigma()]])


def _smooth_residuals(st: BundleState, mid: np.ndarray) -> np.ndarray:
    """(k, 4) second differences at frames ``mid`` in sigmas (0 where a prior is off)."""
    if mid.size == 0 or not _smoothing():
        return np.zeros((0, 4))
    return _second_differences(st, mid) / _sigmas()


def _rot_sigmas() -> np.ndarray:
    """Angular acceleration sigmas (degrees / frame^2) about the camera's x, y (pan, tilt) and z (roll) axes."""
    off = np.inf
    pan_tilt = off if ROT_ACCEL_DEG is None else ROT_ACCEL_DEG
    return np.array([pan_tilt, pan_tilt, off if ROLL_ACCEL_DEG is None else ROLL_ACCEL_DEG])


def _focal_sigma() -> float:
    return np.inf if FOCAL_ACCEL is None else FOCAL_ACCEL


def _smoothing() -> bool:
    """Whether any of the time priors is on (an infinite sigma is off)."""
    return bool(np.isfinite(_rot_sigmas()).any() or np.isfinite(_focal_sigma()))


def _smooth_cost(st: BundleState, mid: np.ndarray) -> float:
    return 0.5 * float(np.sum(_smooth_residuals(st, mid) ** 2))


def _prior_cost(g: np.ndarray, ref: int, g_prior) -> float:
    if g_prior is None:
        return 0.0
    return 0.5 * float(((g[ref] - g_prior[0]) / g_prior[1]) ** 2)


def adjust(state: BundleState, obs: Observations, *, ref: int = 0, g_prior: tuple[float, float] | None = None,
           max_iter: int = 30, tol: float = 1e-7, sigma_px: float | None = None) -> BundleResult:
    """Refine ``state`` (see module docstring).  ``g_prior``: (mean, sigma) of ``g[ref]``; ``sigma_px``: the
    residual scale, else re-estimated from the residuals (MAD) at every iteration."""
    st = BundleState(state.R.copy(), state.g.copy(), state.d.copy())
    lam = 1e-3
    sigma = START_SIGMA_PX if sigma_px is None else sigma_px
    _, proj = project(st, obs)
    e = proj - obs.uv
    if sigma_px is None:
        sigma = _robust_sigma(e)
    mid = _triples(obs)

    def total(state: BundleState, err: np.ndarray) -> float:
        return _cost(err, sigma, _prior_cost(state.g, ref, g_prior) + _smooth_cost(state, mid))

    cost = total(st, e)
    it = 0
    while it < max_iter:
        it += 1
        A, B, C, gc, gp, _ = _normal(st, obs, sigma, ref, g_prior, mid)
        improved = False
        for _ in range(12):
            try:
                dc, dp = _solve(A, B, C, gc, gp, lam)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            trial = _step(st, dc, dp, ref)
            _, proj_t = project(trial, obs)
            et = proj_t - obs.uv
            ct = total(trial, et)
            if np.isfinite(ct) and ct < cost:
                lam = max(lam / 3.0, 1e-9)
                improved = True
                break
            lam *= 10.0
        if not improved:
            break
        rel = (cost - ct) / max(cost, 1e-12)
        st, e = trial, et
        if sigma_px is None:
            new_sigma = _robust_sigma(e)
            if abs(new_sigma - sigma) > 0.05 * sigma:
                sigma = new_sigma
        cost = total(st, e)
        if rel < tol:
            break
    # the variance of g[ref] from the data alone (no prior), for the focal length's determinacy
    A, B, C, *_ = _normal(st, obs, sigma, ref, None, mid)
    var = _marginal_g(A, B, C, ref)
    en = np.linalg.norm(e, axis=1) / sigma
    return BundleResult(st, e, float(sigma), en <= HUBER_K, var, float(cost), it)


def _robust_sigma(e: np.ndarray) -> float:
    """Per-axis standard deviation from the median residual norm (a 2D Gaussian's median norm is 1.1774 sigma)."""
    return max(float(np.median(np.linalg.norm(e, axis=1))) / RAYLEIGH_MEDIAN, 1e-3)


def _normal(st: BundleState, obs: Observations, sigma: float, ref: int, g_prior, mid: np.ndarray):
    """Blocks of the Gauss-Newton normal equations: the cameras' band as its block diagonals
    (lag 0, 1, 2; each (F - lag, 4, 4)), coupling B (F, 4, 2S), points C (2S, 2S) block diagonal,
    gradients gc (F, 4), gp (2S,), and the per-observation weights."""
    F, S = obs.n_frames, obs.n_points
    fi, si = obs.frame, obs.point
    Y, proj = project(st, obs)
    e = (proj - obs.uv) / sigma
    en = np.linalg.norm(e, axis=1)
    wt = np.where(en <= HUBER_K, 1.0, HUBER_K / np.maximum(en, 1e-12))
    z = np.where(np.abs(Y[:, 2]) < 1e-9, 1e-9, Y[:, 2])
    f = np.exp(st.g[fi])
    P = np.zeros((len(fi), 2, 3))
    P[:, 0, 0] = P[:, 1, 1] = f / z
    P[:, 0, 2] = -f * Y[:, 0] / z ** 2
    P[:, 1, 2] = -f * Y[:, 1] / z ** 2
    Jw = -P @ skew(Y)                                             # (m, 2, 3)
    Jg = proj[:, :, None]                                         # (m, 2, 1)
    Jc = np.concatenate([Jw, Jg], axis=2) / sigma                 # (m, 2, 4)
    Jp = P @ st.R[fi] @ tangent_basis(st.d)[si] / sigma           # (m, 2, 2)
    sw = wt[:, None, None]
    D0 = np.zeros((F, 4, 4))
    np.add.at(D0, fi, np.einsum("mka,mkb->mab", Jc * sw, Jc))
    gc = np.zeros((F, 4))
    np.add.at(gc, fi, np.einsum("mka,mk->ma", Jc * sw, e))
    Cb = np.zeros((S, 2, 2))
    np.add.at(Cb, si, np.einsum("mka,mkb->mab", Jp * sw, Jp))
    gpb = np.zeros((S, 2))
    np.add.at(gpb, si, np.einsum("mka,mk->ma", Jp * sw, e))
    B = np.zeros((F, 4, S, 2))
    np.add.at(B, (fi, slice(None), si), np.einsum("mka,mkb->mab", Jc * sw, Jp))
    C = np.zeros((2 * S, 2 * S))
    for s in range(S):
        C[2 * s:2 * s + 2, 2 * s:2 * s + 2] = Cb[s]
    D1 = np.zeros((max(F - 1, 0), 4, 4))
    D2 = np.zeros((max(F - 2, 0), 4, 4))
    if mid.size and _smoothing():
        # second differences with coefficients (1, -2, 1) on frames (mid - 1, mid, mid + 1)
        wgt = np.diag(_sigmas() ** -2.0)
        r = _second_differences(st, mid)
        coef = (1.0, -2.0, 1.0)
        for a in range(3):
            np.add.at(gc, mid - 1 + a, coef[a] * (r @ wgt))
            for b in range(a, 3):
                blk = coef[a] * coef[b] * wgt
                if b == a:
                    np.add.at(D0, mid - 1 + a, blk)
                elif b - a == 1:
                    np.add.at(D1, mid - 1 + a, blk)
                else:
                    np.add.at(D2, mid - 1 + a, blk)
    D0[ref, :3, :3] += np.eye(3) * 1e10                           # the gauge: the reference rotation is held
    if g_prior is not None:
        D0[ref, 3, 3] += 1.0 / g_prior[1] ** 2
        gc[ref, 3] += (st.g[ref] - g_prior[0]) / g_prior[1] ** 2
    return (D0, D1, D2), B.reshape(F, 4, 2 * S), C, gc, gpb.ravel(), wt


def _band(blocks, lam: float) -> np.ndarray:
    """The damped camera matrix in LAPACK's upper banded storage (half-width :data:`_U`)."""
    D0, D1, D2 = blocks
    F = D0.shape[0]
    ab = np.zeros((_U + 1, 4 * F))
    dd = np.einsum("fii->fi", D0)
    D0 = D0 + (lam * dd[:, :, None] + 1e-9) * np.eye(4)
    for lag, D in ((0, D0), (1, D1), (2, D2)):
        if D.shape[0] == 0:
            continue
        rows0 = 4 * np.arange(D.shape[0])
        for p in range(4):
            for q in range(4):
                off = 4 * lag + q - p
                if off < 0:
                    continue
                ab[_U - off, rows0 + 4 * lag + q] = D[:, p, q]
    return ab


def _solve(A, B, C, gc, gp, lam):
    """The damped step: cameras eliminated (Schur complement on the points), then back-substituted."""
    F = B.shape[0]
    ab = _band(A, lam)
    Bf = B.reshape(4 * F, -1)
    Cd = C + lam * np.diag(np.diag(C)) + 1e-9 * np.eye(C.shape[0])
    sol = solveh_banded(ab, np.concatenate([Bf, gc.reshape(-1, 1)], axis=1), check_finite=False)
    AiB, Aig = sol[:, :-1], sol[:, -1]
    Sred = Cd - Bf.T @ AiB
    rhs = -gp + AiB.T @ gc.ravel()
    dp = np.linalg.solve(Sred, rhs)
    dc = -(Aig + AiB @ dp)
    return dc.reshape(F, 4), dp


def _step(st: BundleState, dc: np.ndarray, dp: np.ndarray, ref: int) -> BundleState:
    dw = dc[:, :3].copy()
    dw[ref] = 0.0
    R = rot_and_left_jacobian(dw)[0] @ st.R
    d = st.d + np.einsum("sab,sb->sa", tangent_basis(st.d), dp.reshape(-1, 2))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return BundleState(R, st.g + dc[:, 3], d)


def _marginal_g(A, B, C, ref: int) -> float:
    """Variance of ``g[ref]``: the inverse of the full normal matrix at that entry, through the points'
    Schur complement (``(A^-1)_rr + v^T S^-1 v``, ``v`` row r of ``A^-1 B``)."""
    F = B.shape[0]
    try:
        ab = _band(A, 0.0)
        Bf = B.reshape(4 * F, -1)
        e = np.zeros((4 * F, 1))
        e[4 * ref + 3] = 1.0
        sol = solveh_banded(ab, np.concatenate([Bf, e], axis=1), check_finite=False)
        AiB = sol[:, :-1]
        Sred = C - Bf.T @ AiB + 1e-12 * np.eye(C.shape[0])
        v = AiB[4 * ref + 3]
        return float(sol[4 * ref + 3, -1] + v @ np.linalg.solve(Sred, v))
    except np.linalg.LinAlgError:
        return float("inf")
