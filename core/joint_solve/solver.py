"""The joint least-squares solve: lengths, 3D joints and camera over all frames at once.

Model (see :mod:`core.camera`): the camera stays at the origin of frame 0's
camera axes; frame ``i`` sees a static point ``X`` at ``R_i X`` with
``R_i = exp([w_i])`` and focal ``f_i = exp(g_i)`` (film mm).  The person's
joints ``X_ij`` live in frame-0 camera axes (the static world), so a planted
foot is a *constant* ``X`` – the only static thing in view, and what makes the
camera rotation observable.

Unknowns, stored frame by frame so the normal matrix is banded in time
(55 per frame: 17 joints x 3, ``w_i``, ``g_i``), then the 10 class lengths.

Residuals (each divided by its sigma, so all are unit-free):

* reprojection of every *observed* joint, pixels, Huber-weighted (IRLS);
* bone length ``|X_c - X_p| - L_class`` (symmetric lengths by construction);
* joint acceleration (second difference over time) – carries missing joints
  and removes depth jitter;
* camera rotation and log-focal second differences (smooth camera);
* still foot: the stance ankle does not move between consecutive planted frames;
* optional, for a person standing on the spot: the hips' acceleration held to what standing people's is,
  and each ankle still between consecutive frames where it was found planted;
* knee hinge: a knee may not bend forwards (hinge residual, zero when fine);
* the standing height of the lengths equals ``height_m`` (fixes the global
  scale: a camera at one position only sees ratios);
* optional focal prior ``g_0 = log(hint)`` (a user hint is a prior, not a fixed value);
* optional prior tying the class lengths to another estimate's (the paper's), optionally softer above it,
  with sigmas per class if wanted.
* optional prior on the camera from another estimate (the paper's spell-wise track), with, inside its
  still spells, a tight prior on the change between consecutive frames (a still camera holds still).
* optional depth cue: every bone's unit vector in the frame's camera axes against a direction per frame
  and bone (the pose lifter's, :mod:`core.motion_prior.lifter`), so that a bone the cue is sure of
  does not drift through the picture's plane to its mirror side while the solve settles;
* optional reprojection of static scene points (:mod:`core.scene_camera`), pixels, Huber-weighted: their
  directions are held at the scene camera's solution, so each frame's term involves that frame's
  camera alone and the band stays a band; it is what ties the camera to the scene.

Why our own Levenberg–Marquardt instead of ``scipy.optimize.least_squares``:
with the unknowns ordered frame by frame the normal matrix is a band of
half-width 2 x 55 (second differences reach two frames) plus 10 dense
columns for the lengths.  A banded Cholesky (LAPACK ``pbtrf``) with a Schur
complement for those 10 columns solves an exact Gauss–Newton step in
O(F * 110^2), a few hundredths of a second per 150 frames; SuperLU on the same
matrix took 1-60 s depending on ordering, and ``least_squares``' sparse path
(LSMR inner iterations) converges poorly on these stiff, badly scaled
residuals.  The Jacobian is analytic (rotation through the SO(3) left Jacobian).
The normal equations are summed from the terms' Jacobian blocks straight into the band's parts
(:class:`_NormalEquations`): the Jacobian's sparsity is the same at every iteration of a solve, so where
each product of two of its entries goes is worked out once per solve, not by a sparse product each time.

Tried and not used: a shoulder line kept parallel to the hip line (unit-vector difference, sigma
0.3), meant to give the clavicles a depth and so a length (they come out 0.26 pp short on average,
1.0-1.3 pp on ``neutral`` and ``strutting``).  Over the 15 clips at 1 px it made things worse
(0.229 -> 0.235 pp mean, 81.4 -> 82.6 mm), and worse still with the clavicle's length prior loosened
(0.245 / 1.82 pp; sigma 0.15: 0.278 / 4.68): the true torsos twist by 5-17 degrees on average, and in
most of the skeletons the clavicles are not along the shoulder line (the shoulders are 0.55-0.63 of
two clavicles apart).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dpbtrf, dtbtrs, spbtrf, stbtrs

from ..errors import Cancelled
from ..skeleton import (
    ANKLE_HEIGHT_FRACTION,
    FEET,
    HEIGHT_CLASSES,
    JOINT_INDEX,
    N_CLASSES,
    SEGMENT_CLASS,
    SEGMENTS,
    standing_height,
)
from .blas_threads import single_blas_thread
from .ground import planted_points

NJ = 17
BLOCK = NJ * 3 + 4          # per-frame unknowns
W_OFF = NJ * 3              # offset of w_i in a frame block
G_OFF = NJ * 3 + 3          # offset of g_i

N_GLOBAL = N_CLASSES + 4    # lengths, up vector (3), planted-ankle plane offset
_SEG_P = np.array([p for p, _ in SEGMENTS])
_SEG_C = np.array([c for _, c in SEGMENTS])
_SEG_CLS = np.array(SEGMENT_CLASS)


@dataclass
class Sigmas:
    """Standard deviations of every residual; their ratios are the model's weights."""

    reproj_px: float = 1.0
    huber_px: float = 2.5          # Huber threshold in units of reproj_px
    bone_m: float = 0.002
    #: joint acceleration, m/s^2 (scaled by fps^2 per frame), one sigma for every joint.  The truth's RMS
    #: accelerations (15 clips, 30 fps) are about 5 m/s^2 at the trunk and 10-14 at knees, ankles, elbows and
    #: wrists (medians over clips; 2-37 in all), yet per-joint sigmas measured worse (15 clips, 1 px; proportion
    #: mean / max / mean of clip maxima pp, per-frame MPJPE): 25 everywhere 0.203 / 1.02 / 0.549, 71.7 mm;
    #: trunk 10, limbs 25 0.215 / 1.05 / 0.611, 74.2 mm (and the oracle of bench/ceiling.py 27.0 -> 29.3 mm);
    #: trunk 25, limbs 40 0.211 / 1.23 / 0.577, 73.6 mm.
    accel_ms2: float = 25.0
    rot_accel_deg: float = 0.03    # camera angular acceleration per frame^2
    focal_accel: float = 0.0015    # log-focal acceleration per frame^2
    #: planted ankle drift between frames, Huber at :attr:`foot_huber` sigmas.  The truth's planted ankles
    #: move (contact frames of the 14 shared clips: median 0.5-5 mm a frame, 90th percentile 2.5-10, the heel
    #: lifting) and a stance label can be wrong, so the term is tight for small drift and only linear beyond
    #: it: a wrong label no longer drags the leg.  Tune half of ``bench/motion_bench.py`` (5 clips x 3 draws x
    #: 4 scenarios, cleanup on; means of mirrored frames / per-frame error, median planted excess; paper,
    #: still, detector): 4 mm, no Huber 4.9 / 7.5 / 14.3 %, 55.0 / 55.3 / 73.0 mm, 47 / 68 / 514 mm/s;
    #: 1 mm 5.5 / 10.2 / 16.7 %, 58.3 / 63.3 / 79.9 mm, 18 / -20 / 19 mm/s; 2 mm 5.0 / 9.2 / 16.6 %,
    #: 56.5 / 61.0 / 77.1 mm, 94 / -9 / 93 mm/s; with the Huber at 3 sigmas: 1 mm 4.2 / 6.1 / 14.6 %, 54.5 /
    #: 54.6 / 72.7 mm, 18 / -17 / 335 mm/s; 2 mm 3.6 / 5.9 / 12.3 %, 53.1 / 51.2 / 69.9 mm, 7 / -6 / 552
    #: mm/s; 3 mm 3.5 / 5.8 / 12.0 %, 52.6 / 49.5 / 68.6 mm, 41 / 6 / 706 mm/s; 2 mm at 2 sigmas like 3 mm at
    #: 3; 1.5 mm at 4 sigmas 4.1 / 6.1 / 14.2 %, 54.0 / 54.1 / 72.8 mm, -9 / -15 / 380 mm/s.  The background
    #: scenario within 0.3 points and 0.5 mm throughout.  (Earlier, at 4 mm, a Huber had measured no better
    #: on the proportions of ``python -m core evaluate``.)
    foot_m: float = 0.002
    foot_huber: float | None = 3.0
    floor_m: float = 0.01          # planted ankle height above the common floor plane
    #: torso direction vs the up vector (unit-vector difference).  Loose, so bending people (martial arts,
    #: dance) bend; the price is a depth-vs-lean trade: on strutting (1 px) the solved person walks away 13 %
    #: where the truth walks 24 % and leans every segment further in depth (spine -27 against -13 degrees at
    #: the last frame) to look as small.  Tighter measured worse (15 clips, 1 px; proportion mean / max / mean
    #: of clip maxima pp, per-frame MPJPE): 0.35 0.203 / 1.02 / 0.549, 71.7 mm;  0.2 0.212 / 1.22 / 0.610,
    #: 72.8 mm (strutting's depth-ratio error 3.1 -> 2.6 %, but neutral's 3D error 58 -> 78 mm);  0.12 0.221 /
    #: 1.19 / 0.589, 73.6 mm.
    upright: float = 0.35
    roll_deg: float = 0.2          # camera roll relative to frame 0 (tripod heads keep the horizon)
    rot_speed_deg: float = 0.05    # camera angular speed per frame, Huber (robust: still spells stay still)
    zoom_speed: float = 0.001      # log-focal speed per frame, Huber
    speed_huber: float = 1.0       # Huber threshold of the two speed terms, in sigmas
    #: sine of a forward knee bend.  milad's true knees bend a little forwards (the truth pays 1,388 on this
    #: term), yet looser measured worse (15 clips, 1 px; proportion mean / max / mean of clip maxima pp,
    #: per-frame MPJPE): 0.05 0.203 / 1.02 / 0.549, 71.7 mm;  0.1 0.207 / 1.23 / 0.589, 75.1 mm;  0.1 with
    #: ``elbow`` 0.3 0.208 / 1.14 / 0.616, 76.1 mm.  The hinge steers the search more than it biases the fit.
    knee: float = 0.05
    elbow: float = 0.15            # sine of a backward elbow bend
    head_align: float = 0.35       # neck and head directions vs the upper spine (unit-vector difference)
    spine_straight: float = 0.1    # both spine segments vs the pelvis->thorax line (no kink in depth)
    #: hips centred on the torso axis, shoulders centred left-right.  The truth breaks the first: the pelvis
    #: joint of the CMU, neutral and strutting skeletons sits 3-9 cm behind the hips' midpoint (the true
    #: poses pay 47,420 here on 01_01, 9,824 on 131_01 at 0 px).  A rigid pelvis instead (the hips' midpoint
    #: keeps the clip's mean offset in the body's own axes, held constant in the step) fits the truth
    #: better (bench/ceiling.py's oracle, 1 px: 131_01 23.8 -> 20.2 mm, neutral 34.1 -> 27.3, 01_01 24.8 ->
    #: 24.3, walk_normal 23.7 -> 23.9) but steers the search worse (15 clips, 1 px; proportion mean / max /
    #: mean of clip maxima pp, per-frame MPJPE): zero offset 0.203 / 1.02 / 0.549, 71.7 mm; a forward
    #: offset 0.211 / 1.05 / 0.585, 73.1 mm (131_01 93.7 -> 97.1, neutral 57.8 -> 64.2); forward and lateral
    #: 0.205 / 1.24 / 0.576, 74.6 mm; as 3 polishing iterations after the sign rounds only 0.203 / 1.03 /
    #: 0.561, 71.7 mm (3 more iterations of this term: 0.205 / 1.03 / 0.563, 71.8 mm).
    symmetry_m: float = 0.015
    level: float = 0.15            # up vs frame 0's -y axis (a roughly level camera), unit-vector difference
    #: standing height of the lengths vs the user's height (metres): in effect fixed.  It fixes the scale, and
    #: with the spine and head loosely tied (``pipeline.UPRIGHT_CLASSES``) a short leg makes them long (milad).
    #: 1 cm instead (the paper's length prior still holds the scale), 15 clips, proportion mean / max / mean of
    #: clip maxima pp and per-frame MPJPE: 1 px 0.203 / 1.02 / 0.549, 71.7 mm -> 0.219 / 1.02 / 0.591, 74.0 mm;
    #: 2 px 0.304 / 1.23 / 0.857, 85.3 mm -> 0.301 / 1.10 / 0.761, 84.4 mm (milad 0.446 -> 0.432 pp at 1 px).
    height_m: float = 1e-4
    focal_prior: float = 0.05      # log-focal prior sigma for a user hint (5 %)
    static_px: float = 1.0         # reprojection sigma of static scene points (pixels)


@dataclass
class Problem:
    """Observed data and fixed inputs for one solve."""

    film: np.ndarray               # (F, 17, 2) observed film mm, NaN where missing
    mm_per_px: float
    fps: float
    height_m: float
    stance: np.ndarray             # (F,) int: 0 left, 1 right, -1 none
    sigmas: Sigmas = field(default_factory=Sigmas)
    focal_prior_mm: float | None = None
    focal_prior_sigma: float | None = None
    fixed_lengths: np.ndarray | None = None        # pin the lengths (windowed solves)
    anchors: dict | None = None                    # {"frames": idx, "w": (k,3), "g": (k,), "x": (k,17,3)}
    camera_prior: dict | None = None               # {"w": (F,3) rad, "g": (F,), "sigma_deg", "sigma_log"}
    #                                                sigmas: scalars or (F,) arrays; optionally "still"
    #                                                (F,) bool with "still_sigma_deg", "still_sigma_log":
    #                                                the change between consecutive still frames
    static: dict | None = None                     # {"film": (F, S, 2) mm, NaN where unseen, "dirs": (S, 3)
    #                                                unit directions in frame-0 axes}: static scene points
    bone_cue: dict | None = None                   # {"dirs": (F, 16, 3) unit bone directions in each frame's
    #                                                camera axes, NaN where none, "sigma": unit-vector sigma}
    standing: dict | None = None                   # a person standing on the spot: {"accel_ms2": the hips'
    #                                                acceleration sigma, "feet": (F, 2) bool or None, the frames
    #                                                where each ankle (left, right) is held still as the
    #                                                stance foot is (:attr:`Sigmas.foot_m`)}
    length_prior: tuple | None = None              # (class lengths (10,) m, sigma m[, sigma above m]):
    #                                                another estimate's lengths; the optional third sigma
    #                                                applies where a length exceeds it (one-sided softness);
    #                                                each sigma a scalar or one per class


def initial_ground(joints: np.ndarray, stance: np.ndarray) -> tuple[np.ndarray, float]:
    """Up direction (mean torso direction) and planted-ankle offset along it."""
    torso = joints[:, JOINT_INDEX["thorax"]] - joints[:, JOINT_INDEX["pelvis"]]
    torso = torso / np.maximum(np.linalg.norm(torso, axis=-1, keepdims=True), 1e-9)
    up = torso.mean(axis=0)
    up = up / max(float(np.linalg.norm(up)), 1e-9)
    heights = planted_points(joints, stance) @ up
    if heights.size == 0:
        heights = np.minimum(joints[:, FEET["l"]] @ up, joints[:, FEET["r"]] @ up)
    return up, float(np.median(heights))


def pack(joints: np.ndarray, rotvec: np.ndarray, log_focal: np.ndarray, lengths: np.ndarray,
         up: np.ndarray | None = None, offset: float | None = None, stance: np.ndarray | None = None) -> np.ndarray:
    n = joints.shape[0]
    if up is None or offset is None:
        up, offset = initial_ground(joints, np.full(n, -1) if stance is None else stance)
    blocks = np.concatenate([joints.reshape(n, -1), rotvec, log_focal[:, None]], axis=1)
    return np.concatenate([blocks.ravel(), lengths, up, [offset]])


def unpack(x: np.ndarray, n: int):
    """(joints (F,17,3), rotvec (F,3) rad, log focal (F,), class lengths (10,))."""
    blocks = x[: n * BLOCK].reshape(n, BLOCK)
    return (blocks[:, :W_OFF].reshape(n, NJ, 3), blocks[:, W_OFF:G_OFF], blocks[:, G_OFF],
            x[n * BLOCK:n * BLOCK + N_CLASSES])


def unpack_ground(x: np.ndarray, n: int) -> tuple[np.ndarray, float]:
    """(up unit vector in frame-0 axes, planted-ankle offset along it)."""
    g0 = n * BLOCK + N_CLASSES
    return x[g0:g0 + 3], float(x[g0 + 3])


def huber(en: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray]:
    """IRLS weights and robust costs of residual norms ``en`` (in sigmas) under Huber's loss at ``k``."""
    wt = np.where(en <= k, 1.0, k / np.maximum(en, 1e-12))
    robust = np.where(en <= k, 0.5 * en ** 2, k * en - 0.5 * k * k)
    return wt, robust


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices (..., 3, 3) of vectors (..., 3): ``skew(a) @ b == a x b``."""
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def rot_and_left_jacobian(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R = exp([w]) and the SO(3) left Jacobian J_l(w), both (F, 3, 3)."""
    th = np.linalg.norm(w, axis=-1)[:, None, None]
    k = skew(w)
    k2 = k @ k
    small = th < 1e-6
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0, np.sin(ths) / ths)
    b = np.where(small, 0.5, (1 - np.cos(ths)) / ths ** 2)
    c = np.where(small, 1.0 / 6.0, (ths - np.sin(ths)) / ths ** 3)
    eye = np.eye(3)[None]
    return eye + a * k + b * k2, eye + b * k + c * k2


def _project(Y: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Film projections (m, 2) of camera-axis points ``Y`` (m, 3) at focal ``f`` (m,), and their depths
    kept away from zero (m,)."""
    z = np.where(np.abs(Y[:, 2]) < 1e-6, 1e-6, Y[:, 2])
    return f[:, None] * Y[:, :2] / z[:, None], z


def _projection_jacobian(Y: np.ndarray, z: np.ndarray, f: np.ndarray, scale: float) -> np.ndarray:
    """(m, 2, 3): d(projection x ``scale``) / d ``Y`` for :func:`_project`'s points and depths."""
    dY = np.zeros((len(z), 2, 3))
    fz = f / z * scale
    dY[:, 0, 0] = fz
    dY[:, 1, 1] = fz
    dY[:, 0, 2] = -fz * Y[:, 0] / z
    dY[:, 1, 2] = -fz * Y[:, 1] / z
    return dY


def _projection_turn(Y: np.ndarray, z: np.ndarray, f: np.ndarray, scale: float) -> np.ndarray:
    """(m, 2, 3): ``-dY [Y]`` for :func:`_projection_jacobian`'s ``dY``, written out (``a^T [Y] = (a x Y)^T``
    for its two rows): times ``J_l`` it is the projection's derivative by the camera's rotation vector."""
    x, y = Y[:, 0], Y[:, 1]
    fz = f / z * scale
    out = np.empty((len(z), 2, 3))
    out[:, 0, 0] = -fz * x * y / z
    out[:, 0, 1] = fz * (x * x / z + z)
    out[:, 0, 2] = -fz * y
    out[:, 1, 0] = -fz * (z + y * y / z)
    out[:, 1, 1] = fz * x * y / z
    out[:, 1, 2] = fz * x
    return out


class _Builder:
    """Collects residual rows and Jacobian triplets block by block (one block per :meth:`add`)."""

    def __init__(self):
        self.res, self.cols, self.vals = [], [], []
        self.n_rows = 0

    def add(self, r: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> None:
        """``r`` (m,), ``cols``/``vals`` (m, k): k Jacobian entries per row."""
        self.res.append(r)
        self.cols.append(cols)
        self.vals.append(vals)
        self.n_rows += r.shape[0]

    def build(self, n_cols: int):
        r = np.concatenate(self.res)
        # the rows come block by block in order, so the compressed-row arrays are the blocks' entries as they
        # are: no (row, column) pairs to sort by row.  No row names a column twice (every term's columns are
        # distinct unknowns), so there is nothing to add up; a row's columns stay in the term's order, which
        # the products below do not need sorted (J^T J sums each entry over J's rows in row order either way)
        indptr = np.zeros(self.n_rows + 1, dtype=np.int64)
        np.cumsum(np.concatenate([np.full(c.shape[0], c.shape[1]) for c in self.cols]), out=indptr[1:])
        jac = sp.csr_matrix((np.concatenate([v.ravel() for v in self.vals]),
                             np.concatenate([c.ravel() for c in self.cols]), indptr), shape=(self.n_rows, n_cols))
        return r, jac


def residuals(prob: Problem, x: np.ndarray, with_jac: bool = True, parts: dict | None = None):
    """Weighted residual vector, robust cost, and (optionally) the sparse Jacobian.

    ``parts``, when given, receives the cost of each residual family (diagnostics).
    """
    cost, b = _terms(prob, x, with_jac, parts)
    if not with_jac:
        return cost
    r, jac = b.build(x.size)
    return cost, r, jac


def _terms(prob: Problem, x: np.ndarray, with_jac: bool, parts: dict | None) -> tuple[float, _Builder | None]:
    """The robust cost of :func:`residuals` and, if ``with_jac``, its residual rows and Jacobian entries
    collected in a :class:`_Builder` (which :class:`_NormalEquations` reads without a sparse matrix)."""
    film = prob.film
    n = film.shape[0]
    X, w, g, L = unpack(x, n)
    s = prob.sigmas
    b = _Builder()
    base = np.arange(n) * BLOCK
    lcol = n * BLOCK                       # first length column
    ucol = lcol + N_CLASSES                # up vector columns, then the offset
    up, offset = unpack_ground(x, n)

    # --- reprojection (observed joints only), Huber via IRLS weights
    R, Jl = rot_and_left_jacobian(w)
    Y = X @ np.transpose(R, (0, 2, 1))                             # R X per frame (matmul: einsum is slow here)
    f = np.exp(g)
    obs = np.isfinite(film).all(axis=-1)
    fi, ji = np.nonzero(obs)
    Yo = Y[fi, ji]
    proj, z_safe = _project(Yo, f[fi])
    scale = 1.0 / (prob.mm_per_px * s.reproj_px)
    e = (proj - film[fi, ji]) * scale                    # (m, 2) in sigmas
    enorm = np.linalg.norm(e, axis=-1)
    wt, robust = huber(enorm, s.huber_px)
    sw = np.sqrt(wt)
    cost = float(robust.sum())
    if parts is not None:
        parts["reprojection"] = cost
    if with_jac:
        dY = _projection_jacobian(Yo, z_safe, f[fi], scale)             # d e / d Y: (m, 2, 3)
        dX = dY @ R[fi]                                              # (m, 2, 3)
        dw = _projection_turn(Yo, z_safe, f[fi], scale) @ Jl[fi]     # (m, 2, 3)
        dg = proj * scale                                            # (m, 2)
        cols_x = base[fi, None] + ji[:, None] * 3 + np.arange(3)[None]
        cols_w = base[fi, None] + W_OFF + np.arange(3)[None]
        cols_g = base[fi, None] + G_OFF
        cols = np.concatenate([cols_x, cols_w, cols_g], axis=1)          # (m, 7)
        cols = np.repeat(cols[:, None, :], 2, axis=1).reshape(-1, 7)
        vals = np.concatenate([dX, dw, dg[..., None]], axis=2) * sw[:, None, None]
        b.add((e * sw[:, None]).ravel(), cols, vals.reshape(-1, 7))

    if prob.static is not None:
        # static scene points: the same projection with fixed directions, so only w_i and g_i move
        sfilm = prob.static["film"]
        sobs = np.isfinite(sfilm).all(axis=-1)
        sf, ss = np.nonzero(sobs)
        Ys = np.einsum("mab,mb->ma", R[sf], prob.static["dirs"][ss])
        sproj, zs = _project(Ys, f[sf])
        sscale = 1.0 / (prob.mm_per_px * s.static_px)
        es = (sproj - sfilm[sf, ss]) * sscale
        wts, robust_s = huber(np.linalg.norm(es, axis=-1), s.huber_px)
        cost += float(robust_s.sum())
        if parts is not None:
            parts["static"] = float(robust_s.sum())
        if with_jac:
            dws = _projection_turn(Ys, zs, f[sf], sscale) @ Jl[sf]
            cols = np.concatenate([base[sf, None] + W_OFF + np.arange(3)[None], base[sf, None] + G_OFF], axis=1)
            cols = np.repeat(cols[:, None, :], 2, axis=1).reshape(-1, 4)
            vals = np.concatenate([dws, (sproj * sscale)[..., None]], axis=2) * np.sqrt(wts)[:, None, None]
            b.add((es * np.sqrt(wts)[:, None]).ravel(), cols, vals.reshape(-1, 4))

    def add_quadratic(r, cols, vals, name="other"):
        nonlocal cost
        c = 0.5 * float(np.sum(r * r))
        cost += c
        if parts is not None:
            parts[name] = parts.get(name, 0.0) + c
        if with_jac:
            b.add(r, cols, vals)

    def add_frame_change(v, idx, offs, sigma, name):
        """``(v[i + 1] - v[i]) / sigma`` for the frames ``idx``: ``v`` (F, k) is the per-frame unknowns
        at offsets ``offs`` (k,) of each frame's block (a planted ankle, the camera in a still spell)."""
        if idx.size == 0:
            return
        rr = ((v[idx + 1] - v[idx]) / sigma).ravel()
        c0 = (base[idx, None] + offs[None]).reshape(-1, 1)
        add_quadratic(rr, np.concatenate([c0 + BLOCK, c0], 1), np.tile([1.0 / sigma, -1.0 / sigma], (rr.size, 1)),
                      name)

    def add_robust_change(vv, starts, offs, sigma, k_huber, name):
        """Huber-weighted (IRLS) changes between consecutive frames: ``vv`` (m, k) the changes of the unknowns
        at offsets ``offs`` (k,) from the blocks starting at ``starts`` (m,) to the next frame's, in sigmas;
        the loss is on each row's norm (a camera's turn, an ankle's move), at ``k_huber`` sigmas."""
        nonlocal cost
        if vv.shape[0] == 0:
            return
        wt, robust = huber(np.linalg.norm(vv, axis=1), k_huber)
        c = float(np.sum(robust))
        cost += c
        if parts is not None:
            parts[name] = parts.get(name, 0.0) + c
        if with_jac:
            sq = np.sqrt(wt)[:, None]
            i0 = (starts[:, None] + offs[None]).reshape(-1, 1)
            b.add((vv * sq).ravel(), np.concatenate([i0 + BLOCK, i0], 1),
                  np.repeat(sq, offs.size, axis=0) * np.array([[1.0, -1.0]]) / sigma)

    def add_second_difference(v, offs, sigma, name):
        """``(v[i] - 2 v[i + 1] + v[i + 2]) / sigma`` for every inner frame: ``v`` (F, k) is the per-frame
        unknowns at offsets ``offs`` (k,) of each frame's block (joints, the camera's turn, its log focal)."""
        rr = ((v[:-2] - 2 * v[1:-1] + v[2:]) / sigma).ravel()
        i0 = (base[:-2, None] + offs[None]).reshape(-1)
        cols = np.stack([i0, i0 + BLOCK, i0 + 2 * BLOCK], -1)
        add_quadratic(rr, cols, np.tile([1.0, -2.0, 1.0], (rr.size, 1)) / sigma, name)

    def hold_still(j, idx, name):
        """Joint ``j`` held still from frame ``i`` to ``i + 1`` for the frames ``idx``, as a planted foot is
        (:attr:`Sigmas.foot_m`, robust at :attr:`Sigmas.foot_huber`)."""
        offs = j * 3 + np.arange(3)
        if s.foot_huber is None:
            add_frame_change(X[:, j], idx, offs, s.foot_m, name)
        else:
            add_robust_change((X[idx + 1, j] - X[idx, j]) / s.foot_m, base[idx], offs, s.foot_m, s.foot_huber, name)

    # --- bones
    lengths = L if prob.fixed_lengths is None else prob.fixed_lengths
    d = X[:, _SEG_C] - X[:, _SEG_P]                                   # (F, 16, 3)
    nd = np.maximum(np.linalg.norm(d, axis=-1), 1e-9)
    r = ((nd - lengths[_SEG_CLS][None]) / s.bone_m).ravel()
    u = (d / nd[..., None] / s.bone_m).reshape(-1, 3)
    fr = np.repeat(np.arange(n), len(SEGMENTS))
    cc = base[fr, None] + (np.tile(_SEG_C, n) * 3)[:, None] + np.arange(3)[None]
    cp = base[fr, None] + (np.tile(_SEG_P, n) * 3)[:, None] + np.arange(3)[None]
    cl = (lcol + np.tile(_SEG_CLS, n))[:, None]
    lval = np.full((r.size, 1), -1.0 / s.bone_m if prob.fixed_lengths is None else 0.0)
    add_quadratic(r, np.concatenate([cc, cp, cl], 1), np.concatenate([u, -u, lval], 1), "bones")

    # --- depth cue: (unit(R_i d) - c) / sigma per bone and frame, d the bone in frame-0 axes
    if prob.bone_cue is not None:
        cue = np.asarray(prob.bone_cue["dirs"], dtype=float)
        has = np.isfinite(cue).all(axis=-1)                                    # (F, 16)
        fi_c, si_c = np.nonzero(has)
        if fi_c.size:
            sig_c = float(prob.bone_cue["sigma"])
            Rc = R[fi_c]
            v = np.einsum("mab,mb->ma", Rc, d[fi_c, si_c])                      # bone in camera axes
            nv = np.maximum(np.linalg.norm(v, axis=-1), 1e-9)
            uc = v / nv[:, None]
            rr = ((uc - cue[fi_c, si_c]) / sig_c).ravel()
            cols = vals = None
            if with_jac:
                P = (np.eye(3)[None] - uc[:, :, None] * uc[:, None, :]) / nv[:, None, None] / sig_c   # d unit / d v
                dXc = P @ Rc                                                    # (m, 3, 3)
                # d v / d w = -[v] J_l, and P [v] = [v] / (|v| sigma) = [u] / sigma (u^T [v] = 0)
                dwc = skew(uc / -sig_c) @ Jl[fi_c]
                ccc = base[fi_c, None] + _SEG_C[si_c, None] * 3 + np.arange(3)[None]
                ccp = base[fi_c, None] + _SEG_P[si_c, None] * 3 + np.arange(3)[None]
                ccw = base[fi_c, None] + W_OFF + np.arange(3)[None]
                cols = np.repeat(np.concatenate([ccc, ccp, ccw], 1)[:, None, :], 3, axis=1).reshape(-1, 9)
                vals = np.concatenate([dXc, -dXc, dwc], axis=2).reshape(-1, 9)
            add_quadratic(rr, cols, vals, "bone_cue")

    # --- smoothness of joints, camera rotation, log focal (second differences)
    if n >= 3:
        add_second_difference(X.reshape(n, -1), np.arange(W_OFF), s.accel_ms2 / prob.fps ** 2, "accel")
        add_second_difference(w, W_OFF + np.arange(3), np.radians(s.rot_accel_deg), "rot_accel")
        add_second_difference(g[:, None], np.array([G_OFF]), s.focal_accel, "focal_accel")

    # --- camera speed, robust: most footage holds the camera still between moves, so an L1-like
    #     penalty on speed keeps still spells exactly still without smoothing the moves themselves
    if n >= 2:
        sig_v = np.radians(s.rot_speed_deg)
        vel = (w[1:] - w[:-1]) / sig_v
        zv = (g[1:] - g[:-1]) / s.zoom_speed
        kh = s.speed_huber
        speed_terms = ((vel, W_OFF + np.arange(3), sig_v, "rot_speed"),
                       (zv[:, None], np.array([G_OFF]), s.zoom_speed, "zoom_speed"))
        for vv, offs, sig, name in speed_terms:
            add_robust_change(vv, base[:-1], offs, sig, kh, name)

    # --- prior on the camera from another estimate (the paper's spell-wise tracking)
    if prob.camera_prior is not None:
        cp = prob.camera_prior
        # sigmas: scalars or one per frame (tighter in the prior's still spells)
        sw_ = np.broadcast_to(np.radians(np.asarray(cp["sigma_deg"], dtype=float)), (n,))
        sl_ = np.broadcast_to(np.asarray(cp["sigma_log"], dtype=float), (n,))
        rw = ((w - cp["w"]) / sw_[:, None]).ravel()
        add_quadratic(rw, (base[:, None] + W_OFF + np.arange(3)).reshape(-1, 1),
                      np.repeat(1.0 / sw_, 3)[:, None], "camera_prior")
        rg = (g - cp["g"]) / sl_
        add_quadratic(rg, (base + G_OFF)[:, None], (1.0 / sl_)[:, None], "camera_prior")
        still = cp.get("still")
        if still is not None and n >= 2:
            # inside the prior's still spells the camera holds still but may shift as a block: the
            # change between consecutive still frames gets its own tight sigmas (degrees, log focal)
            idx = np.nonzero(np.asarray(still[:-1], dtype=bool) & np.asarray(still[1:], dtype=bool))[0]
            add_frame_change(w, idx, W_OFF + np.arange(3), np.radians(cp["still_sigma_deg"]), "camera_prior")
            add_frame_change(g[:, None], idx, np.array([G_OFF]), float(cp["still_sigma_log"]), "camera_prior")

    # --- gauge: frame 0's camera is the identity rotation (unless a window is anchored)
    if prob.anchors is None:
        add_quadratic(w[0] / 1e-6, (W_OFF + np.arange(3))[:, None], np.full((3, 1), 1e6))
    else:
        a = prob.anchors
        fr = np.asarray(a["frames"])
        rw = ((w[fr] - a["w"]) / 1e-5).ravel()
        cols = (base[fr, None] + W_OFF + np.arange(3)[None]).reshape(-1, 1)
        add_quadratic(rw, cols, np.full((rw.size, 1), 1e5))
        rg = (g[fr] - a["g"]) / 1e-5
        add_quadratic(rg, (base[fr] + G_OFF)[:, None], np.full((fr.size, 1), 1e5))
        rx = ((X[fr] - a["x"]) / 1e-3).ravel()
        cols = (base[fr, None] + np.arange(W_OFF)[None]).reshape(-1, 1)
        add_quadratic(rx, cols, np.full((rx.size, 1), 1e3))

    # --- still foot
    st = prob.stance
    if n >= 2:
        for side, foot in ((0, FEET["l"]), (1, FEET["r"])):
            hold_still(foot, np.nonzero((st[:-1] == side) & (st[1:] == side))[0], "foot")

    # --- a person standing on the spot: the hips move smoothly, and each ankle holds still from frame to
    #     frame where it was found planted, as the stance foot does (robustly: a wrong one pays linearly)
    if prob.standing is not None and n >= 2:
        feet = prob.standing.get("feet")
        for side, k in enumerate(("l", "r") if feet is not None else ()):
            hold_still(FEET[k], np.nonzero(feet[:-1, side] & feet[1:, side])[0], "standing")
        if n >= 3:
            hips = np.array([JOINT_INDEX[k] for k in ("pelvis", "l_hip", "r_hip")])
            add_second_difference(X[:, hips].reshape(n, -1), (hips[:, None] * 3 + np.arange(3)[None]).ravel(),
                                  prob.standing["accel_ms2"] / prob.fps ** 2, "standing")

    # --- knee hinge (left axis from the current hips, held constant in the step)
    left = X[:, JOINT_INDEX["l_hip"]] - X[:, JOINT_INDEX["r_hip"]]
    left = left / np.maximum(np.linalg.norm(left, axis=-1, keepdims=True), 1e-9)
    # knees bend backwards (sign +1), elbows forwards (sign -1, weaker: the humerus can rotate)
    hinges = [(f"{sd}_hip", f"{sd}_knee", f"{sd}_ankle", 1.0, s.knee, "knee") for sd in "lr"]
    hinges += [(f"{sd}_shoulder", f"{sd}_elbow", f"{sd}_wrist", -1.0, s.elbow, "elbow") for sd in "lr"]
    for a_name, b_name, c_name, sign, sig_h, name in hinges:
        h, kn, an = JOINT_INDEX[a_name], JOINT_INDEX[b_name], JOINT_INDEX[c_name]
        t = X[:, kn] - X[:, h]
        sv = X[:, an] - X[:, kn]
        norm = np.linalg.norm(t, axis=-1) * np.linalg.norm(sv, axis=-1)
        c = sign * np.sum(np.cross(t, sv) * left, axis=-1) / np.maximum(norm, 1e-12)
        active = c < 0
        rr = np.where(active, -c, 0.0) / sig_h
        gt = sign * np.cross(sv, left) / norm[:, None]          # d c / d t
        gs = sign * np.cross(left, t) / norm[:, None]           # d c / d s
        fac = np.where(active, -1.0 / sig_h, 0.0)[:, None]
        cols = np.concatenate([base[:, None] + kn * 3 + np.arange(3), base[:, None] + h * 3 + np.arange(3),
                               base[:, None] + an * 3 + np.arange(3)], 1)
        vals = np.concatenate([(gt - gs) * fac, -gt * fac, gs * fac], 1)
        add_quadratic(rr, cols, vals, name)

    # --- neck and head roughly continue the upper spine, and the spine has no sharp kink: otherwise
    #     these short segments "explain" a wrong depth by pointing at the camera, trading length
    #     between classes under the fixed standing height
    jsp, jth, jnk, jhd = (JOINT_INDEX[k] for k in ("spine", "thorax", "neck", "head"))
    ref = X[:, jth] - X[:, jsp]
    ref_u = ref / np.maximum(np.linalg.norm(ref, axis=-1, keepdims=True), 1e-9)
    jpel = JOINT_INDEX["pelvis"]
    spine_len = np.maximum(np.linalg.norm(X[:, jth] - X[:, jpel], axis=-1), 1e-9)
    spine_ref = (X[:, jth] - X[:, jpel]) / spine_len[:, None]     # pelvis -> thorax, unit
    for p, c, ref_dir, sig_a in ((jth, jnk, ref_u, s.head_align), (jnk, jhd, ref_u, s.head_align),
                                 (jpel, jsp, spine_ref, s.spine_straight), (jsp, jth, spine_ref, s.spine_straight)):
        v = X[:, c] - X[:, p]
        nv = np.maximum(np.linalg.norm(v, axis=-1), 1e-9)
        u = v / nv[:, None]
        rr = ((u - ref_dir) / sig_a).ravel()
        # d u / d v = (I - u u^T) / |v|  (the reference is held constant within a step)
        P = (np.eye(3)[None] - u[:, :, None] * u[:, None, :]) / nv[:, None, None] / sig_a   # (F,3,3)
        cc = base[:, None] + c * 3 + np.arange(3)
        cp = base[:, None] + p * 3 + np.arange(3)
        cols = np.concatenate([np.repeat(cc, 3, axis=0), np.repeat(cp, 3, axis=0)], 1)
        vals = np.concatenate([P.reshape(-1, 3), -P.reshape(-1, 3)], 1)
        add_quadratic(rr, cols, vals, "head")

    # --- left/right symmetry about the torso: without it the pelvis (and thorax) can slide in depth
    #     in front of both hips (shoulders), a "V" that every length and reprojection term allows
    t_u = spine_ref                                              # pelvis -> thorax, held constant
    lh, rh, ls, rs = (JOINT_INDEX[k] for k in ("l_hip", "r_hip", "l_shoulder", "r_shoulder"))
    P_perp = (np.eye(3)[None] - t_u[:, :, None] * t_u[:, None, :]) / s.symmetry_m
    vsum = X[:, lh] + X[:, rh] - 2 * X[:, jpel]
    rr = np.einsum("fab,fb->fa", P_perp, vsum).ravel()
    cols = np.concatenate([np.repeat(base[:, None] + j * 3 + np.arange(3), 3, axis=0) for j in (lh, rh, jpel)], 1)
    vals = np.concatenate([P_perp.reshape(-1, 3), P_perp.reshape(-1, 3), -2 * P_perp.reshape(-1, 3)], 1)
    add_quadratic(rr, cols, vals, "symmetry")
    lat = left / s.symmetry_m                                    # the unit hip line of the hinges
    rr = np.sum(lat * (X[:, ls] + X[:, rs] - 2 * X[:, jth]), axis=-1)
    cols = np.concatenate([base[:, None] + j * 3 + np.arange(3) for j in (ls, rs, jth)], 1)
    add_quadratic(rr, cols, np.concatenate([lat, lat, -2 * lat], 1), "symmetry")

    # --- ground: up is a unit vector, the torso is roughly upright, planted ankles on one plane
    add_quadratic(np.array([(up @ up - 1.0) / 1e-3]), (ucol + np.arange(3))[None], (2 * up / 1e-3)[None], "up")
    # a roughly level frame-0 camera: with footprints on one line (a straight walk) the floor's tilt
    # about that line is otherwise free, and the whole body would lean with it
    add_quadratic((up - np.array([0.0, -1.0, 0.0])) / s.level, (ucol + np.arange(3))[:, None],
                  np.full((3, 1), 1.0 / s.level), "level")
    nt, ut = spine_len, spine_ref                                # the torso, pelvis -> thorax
    rr = ((ut - up[None]) / s.upright).ravel()
    P = (np.eye(3)[None] - ut[:, :, None] * ut[:, None, :]) / nt[:, None, None] / s.upright
    ct = np.repeat(base[:, None] + jth * 3 + np.arange(3), 3, axis=0)
    cpel = np.repeat(base[:, None] + np.arange(3), 3, axis=0)
    cu = np.tile(ucol + np.arange(3), (n, 1)).reshape(n, 3)
    cu = np.repeat(cu, 3, axis=0)
    vu = np.tile(-np.eye(3) / s.upright, (n, 1))
    add_quadratic(rr, np.concatenate([ct, cpel, cu], 1),
                  np.concatenate([P.reshape(-1, 3), -P.reshape(-1, 3), vu], 1), "upright")
    # roll: the camera's x axis keeps its height above the floor (u . R_i^T e_x = u . e_x).
    # With one planted foot in view, rotation about that foot's ray is otherwise free.
    sig_r = np.radians(s.roll_deg)
    xr = R[:, 0, :]                                              # R_i^T e_x = first row of R_i
    rr = (xr @ up - up[0]) / sig_r
    ex = np.array([1.0, 0.0, 0.0])
    dw_roll = np.einsum("fa,fab->fb", (R @ up), skew(ex)[None].repeat(n, 0) @ Jl) / sig_r   # u^T R^T [e_x] J_l
    du_roll = (xr - ex[None]) / sig_r
    cols = np.concatenate([base[:, None] + W_OFF + np.arange(3), np.tile(ucol + np.arange(3), (n, 1))], 1)
    add_quadratic(rr, cols, np.concatenate([dw_roll, du_roll], 1), "roll")
    for side, foot in ((0, FEET["l"]), (1, FEET["r"])):
        idx = np.nonzero(st == side)[0]
        if idx.size == 0:
            continue
        a = X[idx, foot]
        rr = (a @ up - offset) / s.floor_m
        cols = np.concatenate([base[idx, None] + foot * 3 + np.arange(3),
                               np.tile(ucol + np.arange(4), (idx.size, 1))], 1)
        vals = np.concatenate([np.tile(up, (idx.size, 1)), a, -np.ones((idx.size, 1))], 1) / s.floor_m
        add_quadratic(rr, cols, vals, "floor")

    # --- global scale from the standing height; focal prior
    if prob.fixed_lengths is None:
        hsum = float(standing_height(L))
        cols = np.array([[lcol + c for c in HEIGHT_CLASSES]])
        vals = np.full((1, len(HEIGHT_CLASSES)), 1.0 / (1.0 - ANKLE_HEIGHT_FRACTION) / s.height_m)
        add_quadratic(np.array([(hsum - prob.height_m) / s.height_m]), cols, vals)
        if prob.length_prior is not None:
            lp, sig_l = prob.length_prior[:2]
            sig_v = np.broadcast_to(np.asarray(sig_l, dtype=float), (N_CLASSES,)).copy()
            if len(prob.length_prior) > 2 and prob.length_prior[2] is not None:
                sig_v = np.where(L > np.asarray(lp), np.asarray(prob.length_prior[2], dtype=float), sig_v)
            add_quadratic((L - np.asarray(lp)) / sig_v, (lcol + np.arange(N_CLASSES))[:, None],
                          (1.0 / sig_v)[:, None], "length_prior")
        # keep lengths positive and sane: weak pull towards nothing, only a floor
    if prob.focal_prior_mm is not None:
        sig = prob.focal_prior_sigma or s.focal_prior
        add_quadratic(np.array([(g[0] - np.log(prob.focal_prior_mm)) / sig]), np.array([[G_OFF]]),
                      np.array([[1.0 / sig]]))

    return cost, (b if with_jac else None)


@dataclass
class SolveReport:
    cost: float
    iterations: int
    converged: bool


def solve(prob: Problem, x0: np.ndarray, *, max_iter: int = 30, tol: float = 1e-5,
          should_cancel=None, progress=None) -> tuple[np.ndarray, SolveReport]:
    """Levenberg–Marquardt on the sparse normal equations (see module docstring).

    Damping follows Nielsen's rule (shrink by the gain ratio, double the
    growth factor after each rejection), which wastes fewer factorisations on
    rejected steps than fixed x10 / /5 updates.  Stops when an accepted step
    lowers the cost by less than ``tol`` relative.

    The initial damping 1e-3 costs rejected steps (on the 900-frame bench walk 17 factorisations for 11
    iterations), but a larger one takes shorter steps: 1e-2 needs no rejections (5.4 s instead of 6.6 s)
    and ends at a higher cost (40,836 against 38,048), and over the 15 evaluation clips (900 frames max,
    1 px) it gave 0.222 / 1.13 pp and 76.5 mm per frame against 0.203 / 1.02 pp and 71.7 mm.

    A rejected step is tried once more at half its length before the damping is raised and the band
    factored again (:data:`BACKTRACK_ON_REJECT`): one residual evaluation instead of a factorisation.
    """
    x = x0.copy()
    cost, terms = _terms(prob, x, True, None)
    normal = _NormalEquations()
    lam, nu = 1e-3, 2.0
    converged = False
    it = 0
    fixed = None
    if prob.fixed_lengths is not None:
        fixed = np.arange(x.size - N_GLOBAL, x.size - N_GLOBAL + N_CLASSES)
    for it in range(1, max_iter + 1):
        if should_cancel is not None and should_cancel():
            raise Cancelled("cancelled")
        band, grad = normal(terms, x.size, x.size - N_GLOBAL)
        diag = band.diagonal()
        if fixed is not None:
            diag[fixed] += 1.0
        improved = False
        # a trial step's cost comes with its Jacobian's blocks, which the next iteration starts from if the
        # step is taken (the same cost either way; none after the last iteration)
        want_jac = it < max_iter
        for _ in range(10):
            try:
                step = -band.solve(lam * diag + 1e-9, grad)
            except np.linalg.LinAlgError:
                lam *= nu
                nu *= 2.0
                continue
            if fixed is not None:
                step[fixed] = 0.0
            x_new = x + step
            new_cost, new_terms = _terms(prob, x_new, want_jac, None)
            predicted = -(step @ grad) - 0.5 * step @ band.matvec(step)
            rho = (cost - new_cost) / predicted if predicted > 0 else -1.0
            if np.isfinite(new_cost) and new_cost < cost and rho > 0:
                lam *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
                lam = max(lam, 1e-9)
                nu = 2.0
                improved = True
                break
            lam *= nu
            nu *= 2.0
            if BACKTRACK_ON_REJECT:
                x_half = x + 0.5 * step
                half_cost = residuals(prob, x_half, with_jac=False)
                if np.isfinite(half_cost) and half_cost < cost:
                    x_new, new_cost, new_terms, improved = x_half, half_cost, None, True
                    break
        if not improved:
            converged = True
            break
        rel = (cost - new_cost) / max(cost, 1e-12)
        x, cost = x_new, new_cost
        if progress is not None:
            progress(it / max_iter, cost)
        if rel < tol:
            converged = True
            break
        if want_jac:
            terms = new_terms if new_terms is not None else _terms(prob, x, True, None)[1]
    return x, SolveReport(cost=cost, iterations=it, converged=converged)


#: Factor the band in single precision, then refine the step with the double-precision matrix
#: (:data:`REFINE_STEPS` rounds of iterative refinement).  The banded Cholesky is most of the solve's time,
#: and LAPACK's single-precision one is about twice as fast (the 900-frame bench walk's bands: 0.09-0.12 s
#: against 0.19-0.28 s each).  Refined, the step is no less accurate: on that walk's first band the relative
#: residual of the double path's step is 7e-5 (its Schur complement for the lengths loses digits too), of the
#: single one 8e-6 unrefined and 2e-10 after one refinement.  The whole 900-frame estimate took 5.4-5.7 s
#: against 6.5-7.1 s with the double factor, back to back, and ended at the same cost (38,791.040879 against
#: 38,791.040872).  If the single factorisation fails (a band nearly singular), the double one is tried
#: before the step is given up.
SINGLE_PRECISION_FACTOR = True
REFINE_STEPS = 1
#: On a rejected step, try half of it (one residual evaluation) before the damping is raised for the next
#: factorisation; taken if it lowers the cost.  The solves have few iterations (5, 3, 5), and fast limbs
#: (a sprint) make the first steps overshoot, where raising the damping alone spends a factorisation on a
#: shorter, more gradient-like step each time.  Tune half of ``bench/motion_bench.py`` (5 clips x 3 draws,
#: cleanup on), means over cases paper / still / detector / background, without -> with: mirrored frames
#: 7.0 / 10.0 / 16.5 / 7.8 -> 5.0 / 7.5 / 14.4 / 7.8 %, per-frame error 56.7 / 56.4 / 74.4 / 51.1 -> 55.1 /
#: 55.3 / 73.0 / 50.9 mm (most of it on the built-in run: 8 of its 12 cases better by 2-25 mm, none worse by
#: more than 0.3 points); the 15 clips of ``python -m core evaluate`` (1 px): the same proportions, per-frame
#: error equal on 13 clips (one 0.4 mm lower, one 0.4 mm higher).
BACKTRACK_ON_REJECT = True


class _Factors(NamedTuple):
    """A factored, damped normal matrix (``_Band._factor``): the band's Cholesky factor (single or double
    precision), ``W = U^-T C`` and the Schur complement."""

    chol: np.ndarray
    Wc: np.ndarray
    S: np.ndarray


def _triangular_solver(chol: np.ndarray) -> Callable:
    """LAPACK's banded triangular solve in the precision of the Cholesky factor ``chol``."""
    return stbtrs if chol.dtype == np.float32 else dtbtrs


class _Band:
    """Normal matrix split into a band (per-frame unknowns) and the dense global block.

    With the band factored as ``A_b = U^T U`` (LAPACK ``pbtrf``), the global
    unknowns' Schur complement is ``D - W^T W`` with ``W = U^-T C``: one
    forward triangular solve with the 14 global columns per factorisation, then one forward and one
    backward solve with a single column per right-hand side.  ``cho_solve_banded`` would run both
    directions for all 15 columns; LAPACK's banded triangular solves go column by column and are
    memory-bound, so this halves the dominant cost (measured 0.73 s vs 2.0 s per step at 900 frames,
    loaded machine).  The factor is single precision, refined (:data:`SINGLE_PRECISION_FACTOR`).

    The double-precision matrix is kept as the band's lower triangle (CSR) with dense ``C`` and ``D``
    (:meth:`matvec`: the refinement's residual, the solve's predicted reduction); :class:`_NormalEquations`
    assembles these parts straight from the Jacobian's blocks, :meth:`from_matrix` takes them from a
    sparse matrix.  The band in LAPACK's storage is written for each factorisation, straight from the
    lower triangle's entries: about nine in ten of its places stay zero (a frame's unknowns meet the
    next frames' mostly joint by joint), so that is a scatter of the entries there are into zeros.
    """

    def __init__(self, lower: sp.csr_matrix, C: np.ndarray, D: np.ndarray, u: int | None = None,
                 flat: np.ndarray | None = None):
        """``lower``: the band block's lower triangle, diagonal included (nb x nb); ``C`` (nb, ng): the band
        unknowns against the ``ng`` global ones; ``D`` (ng, ng): the global block.  ``u`` and ``flat``, when
        the caller knows them: the half-width, and each of ``lower``'s entries' place in LAPACK's banded
        storage (:meth:`_band`), flattened in column-major order."""
        self.lower = lower
        self.nb = lower.shape[0]
        self.C, self.D = C, D
        if flat is None:
            rows = np.repeat(np.arange(self.nb), np.diff(lower.indptr))        # each entry's row
            u = int((rows - lower.indices).max()) if lower.nnz else 0
            # A[i, j] (i <= j, the lower triangle's entry (j, i)) at ab[u + i - j, j]
            flat = rows * (u + 1) + (u + lower.indices - rows)
        self.u, self._flat = u, flat
        self._diag = lower.diagonal()

    @classmethod
    def from_matrix(cls, A: sp.spmatrix, nb: int) -> _Band:
        """The band of a symmetric sparse matrix whose first ``nb`` unknowns are the band's."""
        A = sp.csr_matrix(A)
        return cls(sp.tril(A[:nb, :nb], format="csr"), A[:nb, nb:].toarray(), A[nb:, nb:].toarray())

    def diagonal(self) -> np.ndarray:
        return np.concatenate([self._diag, np.diag(self.D)])

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """``A @ x`` with the double-precision matrix."""
        nb = self.nb
        xb, xg = x[:nb], x[nb:]
        yb = self.lower @ xb + self.lower.T @ xb - self._diag * xb + self.C @ xg
        return np.concatenate([yb, self.C.T @ xb + self.D @ xg])

    def _band(self, dtype) -> np.ndarray:
        """The band's upper triangle in LAPACK's banded storage: ``A[i, j]`` (``i <= j``, the lower
        triangle's entry ``(j, i)``) at ``ab[u + i - j, j]``, a new array (``pbtrf`` overwrites it)."""
        ab = np.zeros((self.u + 1) * self.nb, dtype=dtype)
        ab[self._flat] = self.lower.data
        return ab.reshape(self.nb, self.u + 1).T                 # Fortran order, as LAPACK reads it

    def _factor(self, damping: np.ndarray) -> _Factors:
        """The damped band factored: in single precision (:data:`SINGLE_PRECISION_FACTOR`) if that succeeds,
        else in double (raising ``LinAlgError`` if the band is not positive definite)."""
        nb = self.nb
        if SINGLE_PRECISION_FACTOR:
            ab = self._band(np.float32)
            ab[self.u] += damping[:nb].astype(np.float32)
            chol, info = spbtrf(ab, lower=0, overwrite_ab=1)
            if info == 0:
                return self._schur(chol, damping)
        ab = self._band(np.float64)
        ab[self.u] += damping[:nb]
        chol, info = dpbtrf(ab, lower=0, overwrite_ab=1)
        if info != 0:
            raise np.linalg.LinAlgError(f"band not positive definite (info {info})")
        return self._schur(chol, damping)

    def _schur(self, chol, damping: np.ndarray) -> _Factors:
        """``W = U^-T C`` and the global unknowns' Schur complement ``S`` for a factored band."""
        trs = _triangular_solver(chol)
        Wc, _ = trs(chol, np.asfortranarray(self.C, dtype=chol.dtype), uplo="U", trans="T", overwrite_b=1)
        Wc = Wc.astype(np.float64)
        return _Factors(chol, Wc, self.D + np.diag(damping[self.nb:]) - Wc.T @ Wc)

    def _apply(self, factors: _Factors, rhs: np.ndarray) -> np.ndarray:
        chol, Wc, S = factors
        trs, dtype = _triangular_solver(chol), chol.dtype
        nb = self.nb
        # a copy: overwrite_b would otherwise write into the caller's rhs (a column view of it is F-contiguous)
        v, _ = trs(chol, np.array(rhs[:nb, None], dtype=dtype, order="F"), uplo="U", trans="T", overwrite_b=1)
        v = v[:, 0].astype(np.float64)
        xg = np.linalg.solve(S, rhs[nb:] - Wc.T @ v)
        xb, _ = trs(chol, np.asfortranarray((v - Wc @ xg)[:, None], dtype=dtype), uplo="U", trans="N",
                    overwrite_b=1)
        return np.concatenate([xb[:, 0].astype(np.float64), xg])

    def solve(self, damping: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        with single_blas_thread():
            factors = self._factor(damping)
            x = self._apply(factors, rhs)
            if factors.chol.dtype == np.float32:
                for _ in range(REFINE_STEPS):
                    x = x + self._apply(factors, rhs - (self.matvec(x) + damping * x))
        return x


def _shared_rows(cols: np.ndarray) -> int:
    """How many consecutive rows of a block name the same columns (3, 2 or 1): a reprojection's two rows, a
    unit vector's three.  Their products with each other are summed per group before they are scattered."""
    m, k = cols.shape
    for s in (3, 2):
        if m and m % s == 0:
            c = cols.reshape(m // s, s, k)
            if (c == c[:, :1]).all():
                return s
    return 1


class _BlockPlan(NamedTuple):
    """Where one :class:`_Builder` block's numbers go in :class:`_NormalEquations`' products."""

    shared: int          # consecutive rows naming the same columns (:func:`_shared_rows`)
    products: slice      # its k(k+1)/2 products per group of rows
    grad: slice          # its entries times their residuals


class _NormalEquations:
    """``J^T J`` (as a :class:`_Band`) and ``J^T r`` straight from a :class:`_Builder`'s blocks.

    Every row of a block names k columns, so its share of ``J^T J`` is the k(k+1)/2 products of its entries
    with each other (the upper triangle of its outer product), rows naming the same columns summed first
    (:func:`_shared_rows`); its share of ``J^T r`` is its k entries times its residual.  Where each product
    goes (which entry of the band's lower triangle, of ``C`` or of ``D``) depends on the blocks' columns
    alone, and those are the same at every iteration of a solve: the observed joints, stance, cues and terms
    do not change within it (hinges and Huber weights change values, not columns).  So that symbolic part
    is worked out once (:meth:`_plan`, again whenever the columns differ), and each iteration is the
    products and one ``np.bincount`` of them into the distinct entries and the gradient.  scipy's
    ``J.T.tocsr() @ J`` redid the symbolic product every iteration, and turning its result into the band
    (to COO, masks, scatter) cost more than the product.

    Measured on the 900-frame bench walk (``bench/bench_estimate.py --frames 900 --methods joint``: 3 solves,
    13 iterations, each function timed in the estimate, two runs each on a 2-core machine with other jobs):
    scipy's path took about 115 ms an iteration (the Jacobian as CSR 10, its transpose 15, the product 39-40,
    the band from it 51-53 ms, then the gradient and the diagonal), this one 80-89 ms an iteration with the
    plan (119-140 ms, once per solve) counted in, about 50 without; the three solves 3.7-3.8 s against
    4.6-4.7 s.  The whole process (bench run as above, A B A B..., 9 pairs): wall median 7.88 s against
    8.31 s, median ratio 0.89; peak memory 286 MiB against 261 (the plan's product-to-entry index).  The
    estimate is the same: its joints within 2e-10 m, the solves' final costs within 1e-11 relative.
    """

    def __init__(self):
        self._cols: list[np.ndarray] | None = None      # the blocks' columns the plan was made for
        self._nb = -1

    def __call__(self, b: _Builder, n_cols: int, nb: int) -> tuple[_Band, np.ndarray]:
        """(``J^T J`` as a band, ``J^T r``) for the builder's rows; the first ``nb`` columns are the band's."""
        if not self._same_columns(b.cols, nb):
            self._plan(b.cols, n_cols, nb)
        w = np.empty(self._slot.size)                      # the products, then the gradient's entries
        for blk, v, r in zip(self._blocks, b.vals, b.res):
            if r.size:
                self._products(v, blk.shared, w[blk.products].reshape(-1, r.size // blk.shared))
                np.multiply(v, r[:, None], out=w[blk.grad].reshape(v.shape))
        values = np.bincount(self._slot, w, minlength=self._n_slots + n_cols)
        nl, nc, nd = self._lower_indices.size, self._c_flat.size, self._d_flat.size
        ng = n_cols - nb
        lower = sp.csr_matrix((values[:nl], self._lower_indices, self._lower_indptr), shape=(nb, nb))
        C = np.zeros(ng * nb)
        C[self._c_flat] = values[nl:nl + nc]
        D = np.zeros(ng * ng)
        D[self._d_flat] = values[nl + nc:nl + nc + nd]
        D = D.reshape(ng, ng)
        return (_Band(lower, C.reshape(ng, nb).T, D + D.T - np.diag(np.diag(D)), u=self._u, flat=self._band_flat),
                values[self._n_slots:])

    @staticmethod
    def _products(v: np.ndarray, s: int, out: np.ndarray) -> None:
        """The upper triangle of each group's ``V^T V`` into ``out`` (k(k+1)/2, groups), ``np.triu_indices``'
        order: with the rows laid out as (s, k, groups), entry i of every group is one contiguous row, and
        the triangle is k broadcast products of a row with the rows after it (9.6 ms an iteration on the
        900-frame bench walk's blocks, against 20.8 ms gathering the pairs' entries with
        ``np.triu_indices``)."""
        k = v.shape[1]
        vt = np.ascontiguousarray(v.reshape(-1, s, k).transpose(1, 2, 0))
        p = 0
        for i in range(k):
            np.multiply(vt[0, i], vt[0, i:], out=out[p:p + k - i])
            for t in range(1, s):
                out[p:p + k - i] += vt[t, i] * vt[t, i:]
            p += k - i

    def _same_columns(self, cols: list[np.ndarray], nb: int) -> bool:
        return (self._cols is not None and self._nb == nb and len(cols) == len(self._cols)
                and all(a.shape == c.shape and np.array_equal(a, c) for a, c in zip(cols, self._cols)))

    def _plan(self, cols: list[np.ndarray], n_cols: int, nb: int) -> None:
        """For each product, the number of its distinct entry of ``J^T J``, those entries ordered as the
        band's lower triangle (by row, then column: CSR), ``C`` (column-major) and ``D``'s upper triangle;
        after them the gradient, by column."""
        self._cols, self._nb = cols, nb
        ng = n_cols - nb
        pairs, shared = [], []
        u = 0                                                              # the band's half-width
        for c in cols:
            shared.append(_shared_rows(c))
            i0, i1 = np.triu_indices(c.shape[1])
            ct = np.ascontiguousarray(c[::shared[-1]].T, dtype=np.int32)  # (k, groups), as the products
            lo, hi = np.minimum(ct[i0], ct[i1]).ravel(), np.maximum(ct[i0], ct[i1]).ravel()
            band = hi < nb
            if band.any():
                u = max(u, int((hi[band] - lo[band]).max()))
            pairs.append((lo, hi, band))
        n_products = sum(lo.size for lo, _, _ in pairs)
        ends = np.cumsum([lo.size for lo, _, _ in pairs] + [c.size for c in cols])
        starts = np.concatenate([[0], ends[:-1]])
        self._blocks = [_BlockPlan(s, slice(starts[i], ends[i]),
                                   slice(starts[len(cols) + i], ends[len(cols) + i]))
                        for i, s in enumerate(shared)]
        # one key per entry: the band's by its place in LAPACK's storage (row hi, then column lo), then C, D
        off_c = (u + 1) * nb
        off_d = off_c + nb * ng
        dtype = np.int32 if off_d + ng * ng < 2 ** 31 else np.int64
        key = np.empty(n_products, dtype=dtype)
        for (lo, hi, band), blk in zip(pairs, self._blocks):
            kk = key[blk.products]
            np.add(hi.astype(dtype) * u, lo + u, out=kk)                   # hi (u + 1) + u - (hi - lo)
            if not band.all():
                lg, hg = lo[~band].astype(dtype), hi[~band].astype(dtype) - nb
                kk[~band] = np.where(lg < nb, off_c + hg * nb + lg, off_d + (lg - nb) * ng + hg)
        del pairs
        used = np.zeros(off_d + ng * ng, dtype=bool)
        used[key] = True
        keys = np.flatnonzero(used)
        self._n_slots = keys.size
        number = np.empty(used.size, dtype=dtype)                          # key -> its entry's number
        number[keys] = np.arange(keys.size, dtype=dtype)
        self._slot = np.empty(ends[-1], dtype=np.intp)
        self._slot[:n_products] = number[key]
        self._slot[n_products:] = np.concatenate([c.ravel() for c in cols])
        self._slot[n_products:] += keys.size
        kb, kc, kd = keys[keys < off_c], keys[(keys >= off_c) & (keys < off_d)], keys[keys >= off_d]
        rows = kb // (u + 1)
        self._lower_indices = (rows - (u - kb % (u + 1))).astype(np.int32)
        self._u, self._band_flat = u, kb                                   # the band entries' places in its storage
        self._lower_indptr = np.zeros(nb + 1, dtype=np.int32)
        np.cumsum(np.bincount(rows, minlength=nb), out=self._lower_indptr[1:])
        self._c_flat = kc - off_c
        self._d_flat = kd - off_d
