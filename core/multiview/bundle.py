"""Bundle adjustment of the views' cameras with the person's constant bones: Levenberg-Marquardt on the
Schur complement.

Unknowns: every view's focal length, the pose of every view but the first (the world is view 1's
camera axes), the 16 bone lengths (left and right apart: real bodies, and a detector's landmarks,
are not symmetric, and forcing them to be bends the lenses), and the 17 joints of every frame.
Residuals: each joint's reprojection in each view that saw it (Huber), each bone's length in each
frame against its length (slack as a share of the bone, Huber beyond three slacks), and view 2's
distance from view 1 (the gauge).

Why not a general sparse solver: the focal lengths are pinned only by how every frame's joints move in
depth together, a long shallow valley that an inexact (LSMR) trust-region step crosses in hundreds of
iterations (measured: 100 iterations left lenses 12-14 % off from a 15 % error, from where the exact
optimum is within 0.02 %). The joints of one frame touch only that frame's residuals, so the normal
equations are block diagonal in the joints: each frame's 51 x 51 block is eliminated exactly and the
step for the few shared unknowns solved densely (the Schur complement), an exact Gauss-Newton step at
the cost of one batched small solve per frame.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..joint_solve.solver import huber, skew
from ..skeleton import N_SEGMENTS, SEGMENTS
from .cameras import ViewCamera

_PAR = np.array([p for p, _ in SEGMENTS])
_CHI = np.array([c for _, c in SEGMENTS])
_CLS = np.arange(N_SEGMENTS)       # each bone its own length
#: Bone residuals (in units of the slack) beyond this count linearly (Huber), not squared.
BONE_HUBER = 3.0


class _Problem:
    """The residuals, cost and Jacobian blocks of one bundle adjustment (see the module docstring)."""

    def __init__(self, cams: list[ViewCamera], pixels: np.ndarray, huber_px: float, slack: float):
        self.v, self.f = pixels.shape[:2]
        self.centres = np.array([c.centre for c in cams])
        obs = np.isfinite(pixels).all(axis=-1)
        self.vi, self.fi, self.ji = np.nonzero(obs)
        self.uv = pixels[self.vi, self.fi, self.ji]
        self.huber = float(huber_px)
        self.slack = float(slack)
        # global unknowns: log focal per view, then (rotation increment, centre) per view after the first,
        # then the log bone lengths
        self.g_focal = np.arange(self.v)
        self.g_rot = self.v + 6 * (np.arange(1, self.v) - 1)[:, None] + np.arange(3)
        self.g_pos = self.g_rot + 3
        self.g_len = self.v + 6 * (self.v - 1) + np.arange(N_SEGMENTS)
        self.n_global = self.v + 6 * (self.v - 1) + N_SEGMENTS

    # ---------------------------------------------------------------- residuals
    def _project(self, R, C, logf, P, base):
        """Every observation's point in its camera's axes y (n_obs, 3), safe depth z, focal f, the
        projection y_xy / z, and the reprojection residual in Huber units."""
        y = np.einsum("oab,ob->oa", R[self.vi], P[self.fi, self.ji] - C[self.vi])
        z = np.maximum(y[:, 2], 1e-6 * base)
        f = np.exp(logf)[self.vi]
        proj = y[:, :2] / z[:, None]
        r = (f[:, None] * proj + self.centres[self.vi] - self.uv) / self.huber
        return y, z, f, proj, r

    def residuals(self, R, C, logf, logL, P, base):
        """(reprojection residuals (n_obs, 2) in Huber units, bone residuals (F, 16), gauge residual)."""
        r_obs = self._project(R, C, logf, P, base)[-1]
        d = P[:, _CHI] - P[:, _PAR]
        L = np.exp(logL)[_CLS]
        r_bone = (np.linalg.norm(d, axis=-1) - L) / (self.slack * L)
        r_gauge = (np.linalg.norm(C[1]) - base) / (1e-3 * base)
        return r_obs, r_bone, r_gauge

    @staticmethod
    def cost(r_obs, r_bone, r_gauge) -> float:
        """Twice :func:`core.joint_solve.solver.huber`'s robust cost: pixels at 1, bones at
        :data:`BONE_HUBER`, the gauge squared."""
        pixels = huber(np.linalg.norm(r_obs, axis=1), 1.0)[1]
        bones = huber(np.abs(r_bone), BONE_HUBER)[1]
        return float(2.0 * (pixels.sum() + bones.sum()) + r_gauge ** 2)

    # ---------------------------------------------------------------- normal equations
    def normal_equations(self, R, C, logf, logL, P, base):
        """(U (G, G), Wt (F, 51, G), V (F, 51, 51), b_g (G,), b_p (F, 51)) of the IRLS Gauss-Newton step."""
        G, F = self.n_global, self.f
        vi, fi, ji = self.vi, self.fi, self.ji
        y, z, f, proj, r = self._project(R, C, logf, P, base)
        w = huber(np.linalg.norm(r, axis=1), 1.0)[0]                         # IRLS weights of the Huber loss
        # d u / d y  (2 x 3), in Huber units
        du_dy = np.zeros((len(vi), 2, 3))
        du_dy[:, 0, 0] = du_dy[:, 1, 1] = f / z
        du_dy[:, :, 2] = -f[:, None] * proj / z[:, None]
        du_dy /= self.huber
        j_point = np.einsum("oay,oyb->oab", du_dy, R[vi])                    # d u / d X
        j_glob = np.zeros((len(vi), 2, G))
        j_glob[np.arange(len(vi)), :, self.g_focal[vi]] = f[:, None] * proj / self.huber
        later = vi > 0
        idx = np.flatnonzero(later)
        rot_cols = self.g_rot[vi[later] - 1]
        pos_cols = self.g_pos[vi[later] - 1]
        j_rot = np.einsum("oay,oyb->oab", du_dy[later], -skew(y[later]))    # left increment: d y = -[y]x d w
        for a in range(3):
            j_glob[idx, :, rot_cols[:, a]] = j_rot[:, :, a]
            j_glob[idx, :, pos_cols[:, a]] = -j_point[later][:, :, a]
        wr = w[:, None] * r
        # observations into the blocks
        U = np.einsum("oag,oah->gh", j_glob * w[:, None, None], j_glob)
        b_g = -np.einsum("oag,oa->g", j_glob, wr)
        V = np.zeros((F, 17, 3, 17, 3))
        jtj = np.einsum("oab,oac->obc", j_point * w[:, None, None], j_point)
        np.add.at(V, (fi, ji, slice(None), ji), jtj)
        Wt = np.zeros((F, 17, 3, G))
        np.add.at(Wt, (fi, ji), np.einsum("oab,oag->obg", j_point * w[:, None, None], j_glob))
        b_p = np.zeros((F, 17, 3))
        np.add.at(b_p, (fi, ji), -np.einsum("oab,oa->ob", j_point, wr))
        # bones: r = (|d| - L) / (s L), d = P_child - P_parent
        d = P[:, _CHI] - P[:, _PAR]
        length = np.maximum(np.linalg.norm(d, axis=-1), 1e-12)
        L = np.exp(logL)[_CLS]
        scale = 1.0 / (self.slack * L)
        rb = (length - L) * scale                                             # (F, 16)
        # Huber on the bones too: a joint a detector put on the wrong limb in the only view that saw it
        # must not bend the cameras; IRLS weights folded into the Jacobian (sqrt) and the residual
        wb = np.sqrt(huber(np.abs(rb), BONE_HUBER)[0])
        rb = rb * wb
        scale = scale * wb
        unit = d / length[..., None] * scale[..., None]                       # d r / d P_child
        dr_dlogL = -length * scale                                            # (F, 16)
        outer = unit[..., :, None] * unit[..., None, :]                       # (F, 16, 3, 3)
        frames = np.repeat(np.arange(F), 16)
        par, chi = np.tile(_PAR, F), np.tile(_CHI, F)
        o3 = outer.reshape(-1, 3, 3)
        np.add.at(V, (frames, chi, slice(None), chi), o3)
        np.add.at(V, (frames, par, slice(None), par), o3)
        np.add.at(V, (frames, chi, slice(None), par), -o3)
        np.add.at(V, (frames, par, slice(None), chi), -o3)
        ub = unit.reshape(-1, 3)
        rbf = rb.reshape(-1)
        np.add.at(b_p, (frames, chi), -ub * rbf[:, None])
        np.add.at(b_p, (frames, par), ub * rbf[:, None])
        cls_cols = self.g_len[np.tile(_CLS, F)]
        dl = dr_dlogL.reshape(-1)
        np.add.at(Wt, (frames, chi, slice(None), cls_cols), ub * dl[:, None])
        np.add.at(Wt, (frames, par, slice(None), cls_cols), -ub * dl[:, None])
        np.add.at(U, (cls_cols, cls_cols), dl ** 2)
        np.add.at(b_g, cls_cols, -dl * rbf)
        # the gauge: view 2's distance from view 1
        dist = max(float(np.linalg.norm(C[1])), 1e-12)
        jg = np.zeros(G)
        jg[self.g_pos[0]] = C[1] / dist / (1e-3 * base)
        rg = (dist - base) / (1e-3 * base)
        U += np.outer(jg, jg)
        b_g -= jg * rg
        return U, Wt.reshape(F, 51, G), V.reshape(F, 51, 51), b_g, b_p.reshape(F, 51)


def _cholesky_solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Solve the symmetric positive definite systems ``A[f] X[f] = B[f]`` ((F, n, n), (F, n, k)).

    A plain batched Cholesky in numpy: ``np.linalg.solve`` on a stack of small matrices hands each
    to the threaded BLAS, which on a busy two-core machine took 0.5-1.3 s for 120 blocks of 51 x 51
    (measured) against 4 ms single-threaded; this loop does not depend on the BLAS's threads.
    """
    n = A.shape[1]
    L = np.zeros_like(A)
    for j in range(n):
        d = A[:, j, j] - np.einsum("fk,fk->f", L[:, j, :j], L[:, j, :j])
        if not np.all(d > 0):
            raise np.linalg.LinAlgError("not positive definite")
        L[:, j, j] = np.sqrt(d)
        if j + 1 < n:
            L[:, j + 1:, j] = (A[:, j + 1:, j] - np.einsum("fik,fk->fi", L[:, j + 1:, :j], L[:, j, :j])) \
                / L[:, j, j][:, None]
    Y = np.zeros_like(B)
    for i in range(n):
        Y[:, i] = (B[:, i] - np.einsum("fk,fkm->fm", L[:, i, :i], Y[:, :i])) / L[:, i, i][:, None]
    X = np.zeros_like(B)
    for i in range(n - 1, -1, -1):
        X[:, i] = (Y[:, i] - np.einsum("fk,fkm->fm", L[:, i + 1:, i], X[:, i + 1:])) / L[:, i, i][:, None]
    return X


def _apply(prob: _Problem, R, C, logf, logL, P, dg, dp):
    R2, C2 = R.copy(), C.copy()
    for k in range(1, prob.v):
        R2[k] = Rotation.from_rotvec(dg[prob.g_rot[k - 1]]).as_matrix() @ R[k]
        C2[k] = C[k] + dg[prob.g_pos[k - 1]]
    return R2, C2, logf + dg[prob.g_focal], logL + dg[prob.g_len], P + dp.reshape(P.shape)


def _state(cams: list[ViewCamera], points: np.ndarray, lengths: np.ndarray):
    """The adjustment's unknowns from cameras, points and lengths: rotations, positions, log focal lengths,
    log lengths, a copy of the points, and the baseline (view 2's distance from view 1) that scales them."""
    C = np.array([c.position for c in cams], dtype=float)
    return (np.array([c.rotation for c in cams], dtype=float), C, np.log([c.focal_px for c in cams]),
            np.log(np.asarray(lengths, dtype=float)), np.array(points, dtype=float), float(np.linalg.norm(C[1])))


def bundle_adjust(cams: list[ViewCamera], pixels: np.ndarray, points: np.ndarray, lengths: np.ndarray, *,
                  slack: float, huber_px: float = 3.0, iterations: int = 60,
                  max_lens_factor: float = 5.0) -> tuple[list[ViewCamera], np.ndarray, np.ndarray, dict]:
    """Refine ``cams`` (view 1 fixed at the origin), ``points`` (F, 17, 3, finite) and the 16 bone
    ``lengths`` against ``pixels`` (V, F, 17, 2). Returns (cameras, points, lengths, report); a step that
    would take a lens beyond ``max_lens_factor`` of where it started, or a length beyond ten times, is
    refused as a failed step."""
    prob = _Problem(cams, pixels, huber_px, slack)
    R, C, logf, logL, P, base = _state(cams, points, lengths)
    logf0, logL0 = logf.copy(), logL.copy()
    cost = prob.cost(*prob.residuals(R, C, logf, logL, P, base))
    start_cost = cost
    lam = 1e-3
    done = 0
    for _ in range(iterations):
        done += 1
        U, Wt, V, b_g, b_p = prob.normal_equations(R, C, logf, logL, P, base)
        improved = False
        for _ in range(8):
            Vd = V + lam * (np.einsum("fii->fi", V)[..., None] * np.eye(51) + 1e-9 * np.eye(51))
            Ud = U + lam * (np.diag(np.diag(U)) + 1e-9 * np.eye(len(U)))
            try:
                both = _cholesky_solve(Vd, np.concatenate([Wt, b_p[..., None]], axis=2))
                Vinv_Wt, Vinv_b = both[..., :-1], both[..., -1]               # (F, 51, G), (F, 51)
                S = Ud - np.einsum("fpg,fph->gh", Wt, Vinv_Wt)
                rhs = b_g - np.einsum("fpg,fp->g", Wt, Vinv_b)
                dg = np.linalg.solve(S, rhs)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            dp = Vinv_b - np.einsum("fpg,g->fp", Vinv_Wt, dg)
            cand = _apply(prob, R, C, logf, logL, P, dg, dp)
            if (np.any(np.abs(cand[2] - logf0) > np.log(max_lens_factor)) or not np.isfinite(cand[4]).all()
                    or np.any(np.abs(cand[3] - logL0) > np.log(10.0))):
                lam *= 10.0
                continue
            new_cost = prob.cost(*prob.residuals(*cand, base))
            if new_cost < cost:
                R, C, logf, logL, P = cand
                improved = cost - new_cost > 1e-7 * cost
                cost = new_cost
                lam = max(lam / 3.0, 1e-9)
                break
            lam *= 4.0
        if not improved:
            break
    out = [ViewCamera(name=c.name, image_size=c.image_size, focal_px=float(np.exp(lf)), rotation=r, position=p)
           for c, lf, r, p in zip(cams, logf, R, C)]
    return out, P, np.exp(logL), {"iterations": done, "cost_start": start_cost, "cost": cost}


def focal_sigma(cams: list[ViewCamera], pixels: np.ndarray, points: np.ndarray, lengths: np.ndarray, *,
                slack: float, huber_px: float = 3.0) -> list[float] | None:
    """Each view's standard deviation of ``log f`` at an adjusted solution (:func:`bundle_adjust`'s
    cameras, points and lengths, the same ``pixels`` and settings): the shared unknowns' covariance (the
    inverse of the Schur complement, the joints eliminated), scaled by the residuals' variance per
    degree of freedom (each frame's 51 joint unknowns absorb much of its pixels' noise, so the residuals
    alone understate it). A lens the bones barely pin shows here. None where it cannot be computed."""
    prob = _Problem(cams, pixels, huber_px, slack)
    R, C, logf, logL, P, base = _state(cams, points, lengths)
    U, Wt, V, _, _ = prob.normal_equations(R, C, logf, logL, P, base)
    # a joint no view saw in a frame is held by its bone alone and free around it: a ridge small against
    # the frame's own curvature keeps those directions (which touch no shared unknown) invertible
    ridge = (1e-9 * np.einsum("fii->f", V)[:, None, None] / 51.0 + 1e-12) * np.eye(51)
    try:
        Vinv_Wt = _cholesky_solve(V + ridge, Wt)
        cov = np.linalg.inv(U - np.einsum("fpg,fph->gh", Wt, Vinv_Wt))
    except np.linalg.LinAlgError:
        return None
    res = prob.residuals(R, C, logf, logL, P, base)
    dof = res[0].size + res[1].size - 51 * prob.f - prob.n_global
    if dof <= 0:
        return None
    scatter = np.sqrt(prob.cost(*res) / dof)             # the cost is the sum of squares below the Huber knee
    return [float(np.sqrt(max(cov[g, g], 0.0)) * scatter) for g in prob.g_focal]
