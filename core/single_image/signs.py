"""Choosing Taylor's depth signs: every one of the 2^16 patterns scored at once.

Under scaled orthography a joint's depth is the sum of its path's ``sign_k * dZ_k``, so all 65,536
sign patterns of a figure are one matrix product; each is scored by how plausible a body it makes
(knees bending backwards, elbows not backwards, hips and shoulders symmetric about the trunk, a
straight spine, the head continuing it: the joint-limit terms of the video solve,
``core.joint_solve.solver``) plus the user's constraints (two joints that coincide, four joints on a
plane: Taylor's closure and coplanarity, section 2.1).  Signs the user gives are held.  A segment is
*ambiguous* when flipping it alone costs less than :data:`AMBIGUOUS_COST` or it lies within
:data:`FLAT_FRACTION` of its length of the image plane.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..motion_prior.features import LEG_BONES
from ..skeleton import JOINT_INDEX, N_JOINTS, SEGMENTS

N_SEG = len(SEGMENTS)
#: Sigmas of the plausibility terms (the video solve's: ``core.joint_solve.solver.Sigmas``).
KNEE, ELBOW, SYMMETRY_M, SPINE, HEAD = 0.05, 0.15, 0.015, 0.1, 0.35
#: Sigma (metres) of a closure or coplanarity constraint.
CONSTRAINT_M = 0.02
AMBIGUOUS_COST = 2.0
FLAT_FRACTION = 0.15
#: The learnt pose prior's weight (:mod:`core.motion_prior`) on twice its negative log-likelihood, the
#: unit of the plausibility terms; 0 leaves the signs to those terms alone.  Which bones it scores:
#: :data:`PRIOR_BONES` (None: every bone the prior has).  Chosen on the tune half (0 px, every 30th frame,
#: 33 frames; P-MPJPE median / mean, frames with a mirrored limb): no prior 77.8 / 92.6 mm, 36.4 %; the legs
#: at weight 1 or 3 72.8 / 87.5 mm, 42.4 %; all four limbs at weight 1 worse (jogging 20 -> 50 % mirrored,
#: 131_01 56 -> 89 %: the training clips hold few running arms).
PRIOR_WEIGHT = 1.0
PRIOR_BONES: tuple[int, ...] | None = LEG_BONES
#: The pose lifter's cue (:mod:`core.motion_prior.lifter`): each bone's cost adds ``|u - c|^2 /
#: LIFTER_SIGMA^2``, ``u`` its unit vector under the pattern's sign and ``c`` the lifter's direction for
#: it; None: no cue.
LIFTER_SIGMA: float | None = 0.2

J = JOINT_INDEX


def _paths() -> np.ndarray:
    """(17, 16): 1 where segment k lies on the path from the root to joint j."""
    A = np.zeros((N_JOINTS, N_SEG))
    for k, (_, c) in enumerate(SEGMENTS):
        A[c] = A[SEGMENTS[k][0]].copy()
        A[c, k] = 1.0
    return A


PATHS = _paths()
ALL_SIGNS = 1.0 - 2.0 * ((np.arange(2 ** N_SEG)[:, None] >> np.arange(N_SEG)[None]) & 1)   # (65536, 16) of +-1


@dataclass
class Constraints:
    """User constraints: ``closures`` pairs of joint indices that coincide; ``coplanar`` 4-tuples on a plane."""

    closures: list = field(default_factory=list)
    coplanar: list = field(default_factory=list)

    @property
    def any(self) -> bool:
        return bool(self.closures or self.coplanar)


def _unit(v):
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def plausibility(X: np.ndarray) -> np.ndarray:
    """Cost (N,) of poses X (N, 17, 3): the sum of squared plausibility residuals."""
    cost = np.zeros(X.shape[0])
    left = _unit(X[:, J["l_hip"]] - X[:, J["r_hip"]])
    for side in "lr":
        for a, b, c, sign, sig in ((f"{side}_hip", f"{side}_knee", f"{side}_ankle", 1.0, KNEE),
                                   (f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist", -1.0, ELBOW)):
            t = X[:, J[b]] - X[:, J[a]]
            s = X[:, J[c]] - X[:, J[b]]
            norm = np.linalg.norm(t, axis=-1) * np.linalg.norm(s, axis=-1)
            h = sign * np.sum(np.cross(t, s) * left, axis=-1) / np.maximum(norm, 1e-12)
            cost += np.where(h < 0, (h / sig) ** 2, 0.0)
    torso = _unit(X[:, J["thorax"]] - X[:, J["pelvis"]])
    v = X[:, J["l_hip"]] + X[:, J["r_hip"]] - 2 * X[:, J["pelvis"]]
    v = v - np.sum(v * torso, axis=-1, keepdims=True) * torso
    cost += np.sum((v / SYMMETRY_M) ** 2, axis=-1)
    lat = np.sum(left * (X[:, J["l_shoulder"]] + X[:, J["r_shoulder"]] - 2 * X[:, J["thorax"]]), axis=-1)
    cost += (lat / SYMMETRY_M) ** 2
    for p, c in (("pelvis", "spine"), ("spine", "thorax")):
        cost += np.sum(((_unit(X[:, J[c]] - X[:, J[p]]) - torso) / SPINE) ** 2, axis=-1)
    upper = _unit(X[:, J["thorax"]] - X[:, J["spine"]])
    for p, c in (("thorax", "neck"), ("neck", "head")):
        cost += np.sum(((_unit(X[:, J[c]] - X[:, J[p]]) - upper) / HEAD) ** 2, axis=-1)
    return np.nan_to_num(cost, nan=0.0)


def constraint_cost(X: np.ndarray, constraints: Constraints) -> np.ndarray:
    """Cost (N,) of the user's closures (distance) and coplanarity (smallest singular value)."""
    cost = np.zeros(X.shape[0])
    for a, b in constraints.closures:
        cost += np.sum(((X[:, a] - X[:, b]) / CONSTRAINT_M) ** 2, axis=-1)
    for quad in constraints.coplanar:
        P = X[:, list(quad)]
        P = P - P.mean(axis=1, keepdims=True)
        sv = np.linalg.svd(P, compute_uv=False)[:, -1]
        cost += (sv / CONSTRAINT_M) ** 2
    return np.nan_to_num(cost, nan=0.0)


def prior_cost(uv: np.ndarray, seg_len: np.ndarray, s: float, pats: np.ndarray, prior) -> np.ndarray:
    """Cost (N,) of sign patterns (N, 16) under the pose prior: ``PRIOR_WEIGHT`` x twice the negative
    log-likelihood of their poses, lowest 0 (all 0 where the prior cannot score them: a limb missing).

    A bone's vector depends on its own sign alone, so the prior's features depend only on the signs
    of the bones it scores and of the four that set the body's frame: those few patterns are scored
    (4,096 at most, against 65,536) and looked up."""
    if prior is None or PRIOR_WEIGHT <= 0:
        return np.zeros(pats.shape[0])
    if PRIOR_BONES is not None:
        prior = prior.restricted(PRIOR_BONES)
    frame = [J["spine"] - 1, J["thorax"] - 1, J["l_hip"] - 1, J["r_hip"] - 1]
    used = sorted(set(frame) | set(prior.bones))
    bits = 2 ** np.arange(len(used))
    codes = ((1 - pats[:, used]) // 2).astype(np.int64) @ bits
    table = np.ones((2 ** len(used), N_SEG))
    table[:, used] = 1.0 - 2.0 * ((np.arange(2 ** len(used))[:, None] >> np.arange(len(used))[None]) & 1)
    ll = prior.log_likelihood(poses(uv, seg_len, s, table))
    if not np.isfinite(ll).any():
        return np.zeros(pats.shape[0])
    ll = np.where(np.isfinite(ll), ll, np.nanmin(ll))
    return PRIOR_WEIGHT * 2.0 * (ll.max() - ll)[codes]


def lifter_cost(uv: np.ndarray, seg_len: np.ndarray, s: float, pats: np.ndarray, cue: np.ndarray | None) -> np.ndarray:
    """Cost (N,) of sign patterns (N, 16) against the lifter's bone directions ``cue`` (16, 3) in the
    camera's axes (NaN rows: no cue for that bone): a bone's term depends on its own sign alone, so
    each pattern's cost is a sum of one of two numbers per bone."""
    if cue is None or LIFTER_SIGMA is None:
        return np.zeros(pats.shape[0])
    dz = depth_steps(uv, seg_len, s)
    cost = np.zeros((2, N_SEG))                                   # row 0: sign +1, row 1: sign -1
    for k, (p, c) in enumerate(SEGMENTS):
        d = (uv[c] - uv[p]) / s
        if not (np.isfinite(d).all() and np.isfinite(cue[k]).all()):
            continue
        for row, sign in enumerate((1.0, -1.0)):
            u = np.array([d[0], d[1], sign * dz[k]])
            u = u / max(float(np.linalg.norm(u)), 1e-12)
            cost[row, k] = float(np.sum((u - cue[k]) ** 2)) / LIFTER_SIGMA ** 2
    return np.where(pats > 0, cost[0], cost[1]).sum(axis=1)


def lifter_cue(uv: np.ndarray, f_px: float) -> np.ndarray | None:
    """(16, 3) the shipped lifter's bone directions for image points ``uv`` (17, 2) about the picture's
    centre, seen with a focal length of ``f_px`` pixels (None when :data:`LIFTER_SIGMA` is None or the
    figure is incomplete)."""
    if LIFTER_SIGMA is None or not np.isfinite(uv).all():
        return None
    from ..motion_prior import load_default_lifter

    rays = np.concatenate([uv, np.full((N_JOINTS, 1), float(f_px))], axis=1)
    return load_default_lifter().bone_directions(rays[None])[0]


def default_prior():
    """The shipped pose prior (:func:`core.motion_prior.load_default`)."""
    from ..motion_prior import load_default

    return load_default()


def depth_steps(uv: np.ndarray, seg_len: np.ndarray, s: float) -> np.ndarray:
    """(16,) non-negative ``dZ`` per segment at scale ``s`` (0 where it does not fit or is missing)."""
    out = np.zeros(N_SEG)
    for k, (p, c) in enumerate(SEGMENTS):
        d2 = float(np.sum((uv[c] - uv[p]) ** 2)) / s ** 2
        if np.isfinite(d2):
            out[k] = np.sqrt(max(seg_len[k] ** 2 - d2, 0.0))
    return out


def poses(uv: np.ndarray, seg_len: np.ndarray, s: float, signs: np.ndarray) -> np.ndarray:
    """Orthographic poses (N, 17, 3) for sign patterns (N, 16), root at depth 0."""
    dz = depth_steps(uv, seg_len, s)
    Z = (signs * dz) @ PATHS.T                                 # (N, 17)
    XY = np.broadcast_to(uv / s, (signs.shape[0], N_JOINTS, 2))
    return np.concatenate([XY, Z[..., None]], axis=-1)


@dataclass
class SignChoice:
    signs: np.ndarray          # (16,) +-1
    cost: float
    ambiguous: list            # segment indices
    flip_cost: np.ndarray      # (16,) extra cost of flipping each segment alone (inf where held)


def choose_signs(uv: np.ndarray, seg_len: np.ndarray, s: float, fixed: dict | None = None,
                 constraints: Constraints | None = None, prior="default", cue: np.ndarray | None = None) -> SignChoice:
    """The cheapest sign pattern at scale ``s`` (module docstring); ``fixed`` {segment index: +-1} is held.

    ``prior``: a :class:`core.motion_prior.PosePrior` whose cost (:func:`prior_cost`) joins the
    plausibility terms, ``"default"`` the shipped one, None none.  ``cue``: the lifter's bone
    directions (:func:`lifter_cue`), whose cost (:func:`lifter_cost`) joins them too."""
    fixed = fixed or {}
    constraints = constraints or Constraints()
    if isinstance(prior, str):
        prior = default_prior()
    pats = ALL_SIGNS
    for k, v in fixed.items():
        pats = pats[pats[:, k] == v]
    X = poses(uv, seg_len, s, pats)
    learnt = prior_cost(uv, seg_len, s, pats, prior)
    cost = plausibility(X) + constraint_cost(X, constraints) + learnt + lifter_cost(uv, seg_len, s, pats, cue)
    best = int(np.argmin(cost))
    signs = pats[best].copy()
    flip = np.full(N_SEG, np.inf)
    # every pattern's position in ``pats`` by its bits (the held segments' bits are the same in all)
    code = ((1 - pats) // 2).astype(np.int64) @ (2 ** np.arange(N_SEG))
    where = dict(zip(code.tolist(), range(len(code))))
    for k in range(N_SEG):
        if k in fixed:
            continue
        alt = signs.copy()
        alt[k] = -alt[k]
        flip[k] = float(cost[where[int(((1 - alt) // 2).astype(np.int64) @ (2 ** np.arange(N_SEG)))]] - cost[best])
    dz = depth_steps(uv, seg_len, s)
    ambiguous = [k for k in range(N_SEG) if k not in fixed and (flip[k] < AMBIGUOUS_COST
                                                               or dz[k] < FLAT_FRACTION * seg_len[k])]
    return SignChoice(signs, float(cost[best]), ambiguous, flip)
