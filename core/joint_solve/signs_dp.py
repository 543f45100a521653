"""Taylor's depth signs resolved over time by dynamic programming.

Every segment has two depth choices per frame (see :mod:`.taylor`): 2^16
poses per frame, 2^(16F) over a clip.  The choices of different limbs hardly
interact, so we split the skeleton into *groups* processed parent-first
(spine, hips with both legs, neck+head, each arm).  Once a group's parents are
placed, the group has 2^k states per frame (k <= 6 segments), and its best
state sequence is a chain problem:

    cost = sum_i unary_i(state_i) + sum_i pairwise_i(state_i, state_{i+1})

* unary: Taylor's shortfall (the ray misses the sphere), joint limits (knees
  bend backwards, elbows forwards – in the body's own left/forward axes),
  hip and shoulder symmetry, clavicles along their hips (the torso twists little),
  each arm swinging against its own leg (a gait assumption, weak);
* pairwise: continuity of the group's segment vectors between frames
  (rotated to frame-0 axes when the camera rotations are known);
* second order: their change of velocity over three frames (a swinging limb
  keeps going through the plane parallel to the image, where the two depth
  candidates meet and first-order continuity ties): :func:`viterbi2` runs the
  chain over pairs of states.

Hips and legs form one group because the hips alone are symmetric under the
depth mirror (facing towards or away): only the knees' bending direction
tells the two apart.  Viterbi solves each group exactly in O(F * 4^k)
instead of 2^(kF) by enumeration;
``tests/core/test_joint_geometry.py`` checks it against brute force.

Why the signs are hard (measured with everything else true: camera, pelvis depth, lengths; 1 px):
near the plane parallel to the image a segment's two candidates come from ``sqrt(L^2 - |p|^2)``,
so 1 px (about 1 cm at 10 m) moves them by 4-10 cm from frame to frame (on the built-in walk the
thigh's candidate depth offset jumps between -0.01 and -0.15 m while the true one glides from -0.11
to +0.07 m).  The DP's crossings therefore land several frames off, in runs with the gait's rhythm,
and its output is 94 mm from the true joints on average (no alignment).

Tried and not used (15 clips, 900 frames, 1 px; mean per-frame MPJPE of the joint method, 81.4 mm
before):

* time-smoothed tracks for the candidates: with everything else true the DP improves (94 -> 72-75 mm
  for a Gaussian of 1.5 frames or a Savitzky-Golay filter of 7-9 frames), but inside the pipeline,
  where the pelvis depth, camera and lengths are estimates, the result gets worse (86.1 mm with
  Savitzky-Golay 9/3, 88.5 mm with the Gaussian);
* a floor cue for the legs (a stance ankle on the planted-ankle plane, no ankle below it; a second DP
  pass after fitting that plane to the first pass): 84.8 mm, and 85.0 mm even with the *true* floor
  (neutral 101 -> 69 mm and 131_01 93 -> 82, but jogging 78 -> 132, side-skip 70 -> 96 and the dance
  82 -> 106, where the camera, and so the floor in each frame's axes, is wrong);
* re-running the DP on the *raw tracks'* rays with the first solve's pelvis depth, camera and lengths
  and solving again (the cheaper of the two kept): 79.2 mm and 0.226 / 1.17 pp against 0.229 / 1.26,
  but the same eight extra iterations without the new DP give 81.0 mm and 0.225 / 1.13 pp, so the
  gain is mostly the iterations, at twice the solve time.

What is used instead: the DP run again on the *solved* rays, which are smooth in time, with a looser
continuity (``core.joint_solve.pipeline.signs_again``; 15 clips at 1 px, 81.2 -> 72.5 mm).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..skeleton import JOINT_INDEX, SEGMENTS, segment_lengths_from_classes
from .taylor import child_candidates

#: Groups of segment child joints, parent groups first.
GROUPS: tuple[tuple[str, ...], ...] = (
    ("spine", "thorax"),
    ("l_hip", "r_hip", "l_knee", "l_ankle", "r_knee", "r_ankle"),
    ("neck", "head"),
    ("l_shoulder", "l_elbow", "l_wrist"),
    ("r_shoulder", "r_elbow", "r_wrist"),
)

#: First-order continuity (metres per frame).  Re-measured with the second order in place (15 clips,
#: 900 frames max; proportion mean / max / mean of clip maxima pp, mean per-frame MPJPE):
#: 0.05 at 0 / 1 / 2 px: 0.196 / 1.72 / 0.606, 79.5 mm;  0.230 / 1.22 / 0.663, 84.9 mm;  0.333 / 1.31 / 0.885,
#: 96.1 mm.  0.08: 0.192 / 1.72 / 0.586, 78.2 mm;  0.229 / 1.26 / 0.665, 81.5 mm;  0.333 / 1.33 / 0.884, 95.3 mm.
#: At 1 px, 0.03: 0.232 / 1.22 / 0.686, 87.6 mm;  0.12: 0.235 / 1.35 / 0.687, 81.5 mm;  0.2: 0.240 / 1.22 /
#: 0.712, 80.4 mm (looser still trades proportions for 3D).
SIGMA_CONTINUITY_M = 0.08
SIGMA_SHORTFALL_M = 0.02
SIGMA_KNEE = 0.05      # 0.1 -> 0.05 measured (6 clips, 1 px): 0.254 -> 0.245 pp mean, 92.4 -> 90.4 mm
SIGMA_ELBOW = 0.1
SIGMA_SYMMETRY_M = 0.03
SIGMA_ABDUCTION = 0.35
#: Clavicle direction vs its hip's (unit-vector difference); None = off.  Measured with SIGMA_ELBOW
#: 0.3 -> 0.1 over 6 synthetic clips (300 frames, 1 px): MPJPE per frame 97.7 -> 92.4 mm, proportion
#: error mean 0.255 -> 0.254 pp, mean of per-clip max 0.650 -> 0.658 pp.
SIGMA_CLAVICLE_HIP = 0.5
#: Upper arm vs same-side thigh swinging the same way (product of their forward sines); None = off.
#: A gait assumption (arms swing against their legs).  Measured over 6 synthetic clips (walk, jogging,
#: 131_03, kick, neutral, side-skip; 300 frames, 1 px): MPJPE per frame 90.4 -> 84.6 mm, lower on
#: every clip (kick 84 -> 76, side-skip 83 -> 71); proportions unchanged (0.245 -> 0.243 pp).
#: With the lifter's cue in the choice the arms follow the lifter, and this term and the clavicle's hardly
#: matter: off (None), the tune half of ``bench/motion_bench.py`` (15 cases a scenario, means over cases
#: paper / still / detector / background) went 4.9 / 7.5 / 14.3 / 7.8 -> 5.1 / 7.5 / 14.6 / 7.9 % mirrored
#: frames and 55.0 / 55.3 / 73.0 / 50.8 -> 54.9 / 55.3 / 73.1 / 51.0 mm; the clavicle's off, within 0.1 of
#: both everywhere.  Both stay.
SIGMA_ARM_SWING = 0.1
#: Second difference over time of the group's segment vectors (metres per frame^2); None = first-order
#: continuity only.  Why: where a segment turns through the plane parallel to the image its two depth
#: candidates meet, so first-order continuity ties between "passes through" and "bounces back"; only
#: the change of velocity tells them apart (a swinging limb keeps going).  Measured with the joint
#: method (second order in every group) on all 15 clips (14 shared + built-in walk, 900 frames max,
#: pan/tilt/zoom, 1 px): proportion error mean / max / mean of clip maxima pp, and the mean over clips
#: of the per-frame MPJPE:
#: None 0.268 / 1.45 / 0.743, 91.1 mm;  0.03: 0.230 / 1.25 / 0.663, 85.9 mm;  0.05: 0.233 / 1.25 /
#: 0.670, 85.5 mm;  0.07: 0.238 / 1.22 / 0.695, 87.7 mm;  0.1: 0.240 / 1.47 / 0.699, 88.2 mm;
#: 0.2: 0.244 / 1.36 / 0.687, 86.1 mm.  Cost: about 1 ms per frame more (the 64-state leg group).
#: With everything else true (camera, pelvis depth, lengths) the gain is smaller (5 clips, 1-15 mm):
#: most wrong signs are whole stretches (the spine leaning the other way all clip), not crossings.
SIGMA_ACCEL_M = 0.05
#: Groups with more states than this (the hips and legs, 64) keep first-order continuity: the second
#: order costs O(F * S^3) and there gains nothing (the knee hinge already settles the legs).  Measured on
#: the same 15 clips: second order in every group 0.233 / 1.25 / 0.670 pp, 85.5 mm, resolve_signs 2.5 s
#: CPU for 900 frames; in every group but the legs 0.230 / 1.22 / 0.663 pp, 84.9 mm, about 1 s less.
SECOND_ORDER_MAX_STATES = 16
#: The pose prior (:mod:`core.motion_prior`) in the choice: its weight on twice the negative
#: log-likelihood (the unit of the other costs here), and how many rounds over the groups it gets
#: once the geometric choice has placed every bone (each group it scores chosen again with the others
#: held).  Chosen on the tune half of ``bench/prior_joint_bench.py`` (5 clips, 300 frames; P-MPJPE per
#: frame, frames with a mirrored limb; moving camera 1 px / still camera 0 px): no prior 92.6 mm 41.4 % /
#: 71.0 mm 26.0 %; weight 1 89.4 mm 40.4 % / 64.3 mm 27.0 %; weight 3 81.3 mm 39.1 % / 66.2 mm 32.0 %, and
#: with the arms keeping their geometric choice (below) 80.0 mm 37.2 % / 61.6 mm 23.5 %.
PRIOR_WEIGHT = 3.0
PRIOR_PASSES = 1
#: The prior's weight on the arm groups, relative to :data:`PRIOR_WEIGHT`; at 0 the arms keep their geometric
#: choice.  The training clips hold few running arms: on the tune half's jogging the prior preferred the
#: elbows in front, and uncapped factor 1 measured 90.0 mm 52.2 % (moving) against 81.3 mm 39.1 % at 0.
#: Factor 1 with :data:`PRIOR_ARM_CAP` 3 won on the tune half but not on the report half
#: (``docs/motion_prior.md``), so the arms stay off.
PRIOR_ARM_FACTOR = 0.0
#: The trunk's and legs' groups scored by the prior's legs alone (its marginal over the thighs and shanks,
#: :meth:`core.motion_prior.PosePrior.restricted`) instead of all four limbs.  Measured on the tune half
#: (weight 3): 94.6 mm 41.8 % / 62.6 mm 25.2 %, no better than the limbs (81.3 mm 39.1 % / 66.2 mm 32.0 %).
PRIOR_LEGS_ALONE = False
#: The arms' weighted prior cost capped at this many units per frame (None: no cap), when
#: :data:`PRIOR_ARM_FACTOR` > 0: the prior then decides only where the geometric costs of an arm's states
#: nearly tie, and cannot overrule a clear geometric choice (the jogging elbows above).  Tune half (5 clips,
#: 300 frames; moving 1 px / still 0 px; P-MPJPE per frame, frames with a mirrored limb), factor 1: arms
#: without the prior 80.4 mm 37.5 % / 62.2 mm 23.5 %; cap 0.5 81.1 mm 38.1 % / 66.0 mm 30.7 %; 1: 82.0 mm
#: 35.9 % / 62.9 mm 24.6 %; 2: 82.4 mm 35.5 % / 58.8 mm 20.8 %; 3: 80.4 mm 31.9 % / 59.6 mm 21.9 %; 4:
#: 80.7 mm 34.8 % / 63.3 mm 26.0 %; 6: 83.2 mm 36.4 % / 62.5 mm 30.2 %; cap 3 at factor 0.5: 81.8 mm 34.5 %
#: / 57.8 mm 22.6 %.  Report half (11 clips), cap 3 against the arms without the prior: moving 88.5 mm
#: 26.8 % against 83.5 mm 30.2 %, still 78.4 mm 30.5 % against 73.1 mm 28.0 %.
PRIOR_ARM_CAP: float | None = 3.0
#: The depth cue (a bone direction per frame from the pose lifter, :mod:`core.motion_prior.lifter`, or
#: the detector's own 3D): each state's cost adds ``|u - c|^2 / SIGMA_CUE^2`` per bone of the group, ``u``
#: the state's unit bone vector and ``c`` the cue's, in the camera's axes.  A bone flipped in depth with
#: depth over length ``d`` moves ``u`` by ``2 d``.
SIGMA_CUE = 0.3
#: Groups the cue takes part in (the first group's name); all by default.
CUE_GROUPS: tuple[str, ...] = ("spine", "l_hip", "neck", "l_shoulder", "r_shoulder")
#: The prior scores only this many of a group's states per frame, the cheapest by every other cost of the
#: state (None: all).  The others get the frame's highest scored cost.  The prior is most of the legs' cost
#: (64 states a frame), and the state the DP keeps is nearly always among the cheapest by the rest.  Tune
#: half of ``bench/motion_bench.py`` (5 clips x 3 draws, cleanup on; means over cases paper / still /
#: detector / background), all states -> 16: mirrored frames 5.0 / 7.5 / 14.4 / 7.8 -> 4.9 / 7.5 / 14.3 /
#: 7.8 %, per-frame error 55.1 / 55.3 / 73.0 / 50.9 -> 55.0 / 55.3 / 73.0 / 50.8 mm.  The 900-frame bench
#: walk's two sign choices: 1.8-2.1 s -> 1.6-1.7 s (with 32 its answer is the same to the bit).
PRIOR_STATES: int | None = 16


def _prior_factor(group) -> float:
    """The prior's weight on ``group`` relative to :data:`PRIOR_WEIGHT` (:data:`PRIOR_ARM_FACTOR` for the arms)."""
    return PRIOR_ARM_FACTOR if group[0] in ("l_shoulder", "r_shoulder") else 1.0


def _legs_prior(prior):
    """``prior`` restricted to the legs' bones (cached on the prior)."""
    from ..motion_prior.features import LEG_BONES

    cached = getattr(prior, "_legs", None)
    if cached is None:
        cached = prior.restricted(LEG_BONES)
        prior._legs = cached
    return cached


def viterbi(unary: np.ndarray, pairwise: np.ndarray) -> np.ndarray:
    """Minimum-cost state path (F,) for unary (F, S) and pairwise (F-1, S, S) costs."""
    n, n_states = unary.shape
    acc = unary[0].copy()
    back = np.zeros((n, n_states), dtype=np.int64)
    for i in range(1, n):
        total = acc[:, None] + pairwise[i - 1]  # from state (rows) -> to state (cols)
        back[i] = np.argmin(total, axis=0)
        acc = total[back[i], np.arange(n_states)] + unary[i]
    path = np.zeros(n, dtype=np.int64)
    path[-1] = int(np.argmin(acc))
    for i in range(n - 1, 0, -1):
        path[i - 1] = back[i, path[i]]
    return path


def viterbi2(unary: np.ndarray, pairwise: np.ndarray, vecs: np.ndarray, sigma: float) -> np.ndarray:
    """Minimum-cost path (F,) with a second-order term: ``|v_{i-1} - 2 v_i + v_{i+1}|^2 / sigma^2``.

    ``vecs`` (S, F, D) are each state's vector per frame.  The chain runs over state *pairs*
    (previous, current), so it costs O(F * S^3) time and O(F * S^2) memory: fine for S <= 64.
    """
    n, n_states = unary.shape
    if n < 3:
        return viterbi(unary, pairwise)
    inv = 1.0 / sigma ** 2
    v = np.ascontiguousarray(np.transpose(vecs, (1, 0, 2)))          # (F, S, D)
    sq = np.sum(v ** 2, axis=-1)                                      # (F, S)
    near = v[:-1] @ np.transpose(v[1:], (0, 2, 1))                    # (F-1, S, S): frames i-1, i
    # |a - 2b + c|^2 split by which states each term involves, all frames at once, so that only the
    # a-c cross term is added inside the minimum over a (the others are folded in before or after it)
    before = (sq[:-2, :, None] + 4.0 * sq[1:-1, None, :] - 4.0 * near[:-1]) * inv          # (a, b)
    after = (sq[2:, None, :] - 4.0 * near[1:]) * inv + pairwise[1:] + unary[2:, None, :]  # (b, c)
    # in double precision throughout: the chains run here have at most :data:`SECOND_ORDER_MAX_STATES`
    # states, arrays of a few hundred numbers a frame, where a single-precision pass saves nothing
    skip = (2.0 * inv) * (v[:-2] @ np.transpose(v[2:], (0, 2, 1)))   # (a, c)
    acc = unary[0][:, None] + pairwise[0] + unary[1][None, :]         # (prev, cur) at frame 1
    back = np.zeros((n, n_states, n_states), dtype=np.int16)
    for i in range(2, n):
        total = (acc + before[i - 2])[:, :, None] + skip[i - 2][:, None, :]
        back[i] = np.argmin(total, axis=0)                            # (cur, next)
        acc = total.min(axis=0) + after[i - 2]                       # = total[k], one pass cheaper
    path = np.zeros(n, dtype=np.int64)
    path[-2], path[-1] = np.unravel_index(int(np.argmin(acc)), acc.shape)
    for i in range(n - 1, 1, -1):
        path[i - 2] = back[i, path[i - 1], path[i]]
    return path


def _left_axis(l_hip: np.ndarray, r_hip: np.ndarray) -> np.ndarray:
    """The body's unit left axis (..., 3): from the right hip to the left."""
    left = l_hip - r_hip
    return left / np.maximum(np.linalg.norm(left, axis=-1, keepdims=True), 1e-9)


def _body_axes(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit left and forward axes (F, 3) from hips and spine (right-handed camera axes)."""
    j = JOINT_INDEX
    left = _left_axis(joints[:, j["l_hip"]], joints[:, j["r_hip"]])
    up = joints[:, j["thorax"]] - joints[:, j["pelvis"]]
    fwd = np.cross(left, up)
    fwd = fwd / np.maximum(np.linalg.norm(fwd, axis=-1, keepdims=True), 1e-9)
    return left, fwd


def hinge_violation(upper: np.ndarray, lower: np.ndarray, left: np.ndarray, sign: float) -> np.ndarray:
    """How much a hinge bends the wrong way (>= 0), as a sine.

    Knees (``sign=+1``) need ``(upper x lower) . left >= 0`` (the shank swings
    backwards), elbows (``sign=-1``) the opposite.
    """
    c = np.sum(np.cross(upper, lower) * left, axis=-1)
    norm = np.linalg.norm(upper, axis=-1) * np.linalg.norm(lower, axis=-1)
    return np.maximum(0.0, -sign * c / np.maximum(norm, 1e-12))


def resolve_signs(rays: np.ndarray, class_lengths: np.ndarray, depth: np.ndarray,
                  rotations: np.ndarray | None = None,
                  continuity_m: float | None = None, prior=None,
                  prior_weight: float | None = None, cue: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Choose every segment's depth sign over the clip.

    ``rays`` (F, 17, 3) unit rays in each frame's camera axes; ``depth`` (F,)
    pelvis depth; ``rotations`` (F, 3, 3) optional ``R_i`` to compare segment
    vectors in frame-0 axes; ``continuity_m`` overrides :data:`SIGMA_CONTINUITY_M`.
    ``prior``: a :class:`core.motion_prior.PosePrior`; with it, every group is chosen again
    (:data:`PRIOR_PASSES` times) with the prior's cost of each state, the other groups held
    (:func:`_prior_cost`), weighted by ``prior_weight`` (default :data:`PRIOR_WEIGHT`).
    ``cue`` (F, 16, 3): unit bone directions in each frame's camera axes that every state is compared
    with (:data:`SIGMA_CUE`; NaN: no cue for that bone and frame).
    Returns (signs (F, 16) of +-1, joints (F, 17, 3) in each frame's camera axes).
    """
    sigma_cont = SIGMA_CONTINUITY_M if continuity_m is None else float(continuity_m)
    n = rays.shape[0]
    seg_len = segment_lengths_from_classes(class_lengths)
    joints = np.full((n, 17, 3), np.nan)
    joints[:, 0] = rays[:, 0] * (depth / rays[:, 0, 2])[:, None]
    signs = np.ones((n, len(SEGMENTS)))
    to_world = None if rotations is None else np.transpose(rotations, (0, 2, 1))
    # a group's own costs (all but the prior's) depend on a few joints placed before it (:func:`_reads`): kept
    # with a copy of those, they serve the prior's rounds while those joints stand
    weight = PRIOR_WEIGHT if prior_weight is None else float(prior_weight)
    rounds = prior is not None and weight > 0
    built = {}
    for group in GROUPS:
        before = joints[:, _reads(group)].copy()
        states = _choose_group(group, rays, seg_len, joints, signs, to_world, sigma_cont, cue=cue)
        if rounds and _prior_factor(group) > 0:
            built[group] = (before, states)
    if not rounds:
        return signs, joints
    for _ in range(PRIOR_PASSES):
        for group in GROUPS:
            if _prior_factor(group) <= 0:
                continue          # its signs stay; its joints follow their parents (the rebuild)
            before, states = built[group]
            if not np.array_equal(joints[:, _reads(group)], before, equal_nan=True):
                states = None
            _choose_group(group, rays, seg_len, joints, signs, to_world, sigma_cont, prior, weight, cue=cue,
                          states=states)
            joints = _rebuild(rays, seg_len, joints[:, 0], signs)
    return signs, joints


#: The joints outside a group that its plausibility terms read (:func:`_group_prior`), by its first joint.
#: An arm reads the body's axes (hips, pelvis, thorax) and its own side's knee (the arm's swing).
_PLAUSIBILITY_READS = {"l_hip": ("pelvis",),
                       "l_shoulder": ("pelvis", "thorax", "l_hip", "r_hip", "l_knee"),
                       "r_shoulder": ("pelvis", "thorax", "l_hip", "r_hip", "r_knee")}


def _reads(group) -> list[int]:
    """The joints outside ``group`` that its states and costs but the prior's (:func:`_group_states`) are
    built from: its chains' parents and what its plausibility terms read."""
    children = [JOINT_INDEX[name] for name in group]
    out = {SEGMENTS[c - 1][0] for c in children} - set(children)
    out |= {JOINT_INDEX[name] for name in _PLAUSIBILITY_READS.get(group[0], ())}
    return sorted(out)


def _rebuild(rays, seg_len, root, signs) -> np.ndarray:
    """Joints (F, 17, 3) from the root, the rays and every segment's sign (+1 the far candidate)."""
    out = np.empty(rays.shape[:1] + (17, 3))
    out[:, 0] = root
    for s, (p, c) in enumerate(SEGMENTS):
        near, far, _ = child_candidates(out[:, p], rays[:, c], seg_len[s])
        out[:, c] = np.where((signs[:, s] > 0)[:, None], far, near)
    return out


def _prior_cost(prior, joints: np.ndarray, children: list[int], vecs: np.ndarray) -> np.ndarray:
    """(F, S): twice the prior's negative log-likelihood of the pose with the group's bones (``children``)
    set to each state's vectors ``vecs`` (S, F, k, 3) and every other bone as in ``joints``; its
    per-frame minimum taken off (a constant per frame does not change the path)."""
    from ..motion_prior.features import bone_vectors

    bones = bone_vectors(joints)                                   # (F, 16, 3)
    n_states = vecs.shape[0]
    trial = np.repeat(bones[None], n_states, axis=0)               # (S, F, 16, 3)
    for b, c in enumerate(children):
        trial[:, :, c - 1] = vecs[:, :, b]
    cost = -2.0 * prior.log_likelihood_bones(trial).T              # (F, S)
    cost = np.nan_to_num(cost, nan=0.0, posinf=0.0)
    return cost - cost.min(axis=1, keepdims=True)


def _pruned_prior_cost(prior, joints: np.ndarray, children: list[int], vecs: np.ndarray, unary: np.ndarray,
                       keep: int) -> np.ndarray:
    """:func:`_prior_cost` (F, S) scored for the ``keep`` states of each frame cheapest by ``unary`` (F, S);
    the others get the frame's highest scored cost."""
    n = unary.shape[0]
    idx = np.argpartition(unary, keep - 1, axis=1)[:, :keep]                 # (F, keep)
    rows = np.arange(n)[:, None]
    scored = _prior_cost(prior, joints, children, vecs[idx.T, rows.T])       # (F, keep)
    cost = np.repeat(scored.max(axis=1, keepdims=True), unary.shape[1], axis=1)
    cost[rows, idx] = scored
    return cost


def _cue_cost(cue: np.ndarray, children: list[int], vecs: np.ndarray, deps: list[int] | None = None) -> np.ndarray:
    """(F, S): the group's bones' distance from the cue's directions (:data:`SIGMA_CUE`), per state.

    ``deps[b]``: the state bits bone ``b``'s vector depends on (:func:`_state_bits`); each bone's distance is
    then worked out once per distinct vector, not once per state (all the same numbers)."""
    n_states = vecs.shape[0]
    if deps is None:
        deps = [n_states - 1] * len(children)
    per_bone = []
    for b, ch in enumerate(children):
        reps, expand = _sub_states(n_states, deps[b])
        v = vecs[reps, :, b]                                                   # (R, F, 3)
        u = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)
        per_bone.append((np.sum((u - cue[None, :, ch - 1]) ** 2, axis=-1) / SIGMA_CUE ** 2)[expand])
    return np.nan_to_num(np.stack(per_bone, axis=-1), nan=0.0).sum(axis=-1).T


def _sub_states(n_states: int, mask: int) -> tuple[np.ndarray, np.ndarray]:
    """The states whose bits all lie in ``mask`` (one for each setting of those bits), and for every state
    the index among them of the one that agrees with it on ``mask``.  A quantity that depends only on the
    bits in ``mask`` is worked out on the first and spread to all states with the second."""
    states = np.arange(n_states)
    reps = np.flatnonzero((states & ~mask) == 0)
    return reps, np.searchsorted(reps, states & mask)


def _state_bits(group) -> tuple[list[int], list[int]]:
    """For each joint of ``group`` (state bit ``b`` picks its far candidate), the bits its place depends on:
    its ancestors' in the group (``ancestors``), and those with its own (``deps``)."""
    children = [JOINT_INDEX[name] for name in group]
    ancestors = [0] * len(children)
    for b, c in enumerate(children):
        p = SEGMENTS[c - 1][0]
        if p in children:
            ancestors[b] = ancestors[children.index(p)] | (1 << children.index(p))
    return ancestors, [a | (1 << b) for b, a in enumerate(ancestors)]


class _GroupStates(NamedTuple):
    """A group's states and the costs that do not involve the pose prior (:func:`_group_states`)."""

    cand: np.ndarray        # (S, F, k, 3) each state's child positions, camera axes
    vecs: np.ndarray        # (S, F, k, 3) its segment vectors, camera axes
    unary: np.ndarray       # (F, S) shortfall, plausibility and cue costs
    pairwise: np.ndarray    # (F-1, S, S) first-order continuity
    flat: np.ndarray        # (S, F, 3k) segment vectors as compared over time (frame-0 axes if known)


def _choose_group(group, rays, seg_len, joints, signs, to_world, sigma_cont, prior=None, weight=0.0,
                  cue=None, states: _GroupStates | None = None) -> _GroupStates:
    """One group's states chosen by the DP; ``joints`` and ``signs`` updated in place for its joints.
    ``states``: the group's states and costs already built from the same joints it reads (:func:`_reads`;
    the prior's cost is added to a copy).  Returns them."""
    if states is None:
        states = _group_states(group, rays, seg_len, joints, to_world, sigma_cont, cue)
    n = rays.shape[0]
    children = [JOINT_INDEX[name] for name in group]
    n_states = states.unary.shape[1]
    unary = states.unary
    if prior is not None:
        arms = group[0] in ("l_shoulder", "r_shoulder")
        factor = _prior_factor(group)
        if factor > 0:
            if not arms and PRIOR_LEGS_ALONE:
                prior = _legs_prior(prior)
            if PRIOR_STATES is not None and n_states > PRIOR_STATES:
                cost = _pruned_prior_cost(prior, joints, children, states.vecs, unary, PRIOR_STATES)
            else:
                cost = _prior_cost(prior, joints, children, states.vecs)
            cost *= factor * weight
            if arms and PRIOR_ARM_CAP is not None:
                cost = np.minimum(cost, PRIOR_ARM_CAP)
            unary = unary + cost
    if SIGMA_ACCEL_M is None or n_states > SECOND_ORDER_MAX_STATES:
        path = viterbi(unary, states.pairwise)
    else:
        path = viterbi2(unary, states.pairwise, states.flat, SIGMA_ACCEL_M)
    rows = np.arange(n)
    for b, c in enumerate(children):
        joints[:, c] = states.cand[path, rows, b]
        signs[:, c - 1] = np.where((path >> b) & 1, 1.0, -1.0)
    return states


def _group_states(group, rays, seg_len, joints, to_world, sigma_cont, cue) -> _GroupStates:
    """A group's 2^k states (every depth sign of its k segments, its parents placed in ``joints``) and
    their costs but the pose prior's."""
    n = rays.shape[0]
    children = [JOINT_INDEX[name] for name in group]
    k = len(children)
    n_states = 2 ** k
    cand = np.empty((n_states, n, k, 3))       # child positions per state
    vecs = np.empty((n_states, n, k, 3))       # segment vectors per state
    unary = np.zeros((n, n_states))
    # a child's two candidates depend only on its parent's place, so on the states of its ancestors in the
    # group: computed once per such state (a leg's ankle 4 times, not once for each of the 64 states)
    ancestors, deps = _state_bits(group)
    for b, c in enumerate(children):
        p = SEGMENTS[c - 1][0]
        reps, expand = _sub_states(n_states, ancestors[b])
        parent = cand[reps, :, children.index(p)] if p in children else joints[None, :, p]   # (R or 1, F, 3)
        near, far, short = child_candidates(parent, rays[:, c], seg_len[c - 1])
        both = np.stack(np.broadcast_arrays(near, far))                          # (2, R, F, 3)
        pick = ((np.arange(n_states) >> b) & 1, expand)                         # near or far, of which parent
        cand[:, :, b] = both[pick]
        vecs[:, :, b] = (both - parent)[pick]
        unary += ((np.broadcast_to(short, (reps.size, n)) / SIGMA_SHORTFALL_M) ** 2)[expand].T
    # the plausibility terms of every state at once: each joint's places (S, F, 3) side by side
    states_prior = _group_prior(group, joints, {c: cand[:, :, b] for b, c in enumerate(children)}, deps)
    unary += np.broadcast_to(states_prior, (n_states, n)).T
    if cue is not None and group[0] in CUE_GROUPS:
        unary += _cue_cost(cue, children, vecs, deps)
    # compared over time in frame 0's axes when the turns are known: R^T v per frame (matmul: einsum is slow)
    flat = vecs if to_world is None else vecs @ np.swapaxes(to_world, 1, 2)[None]
    flat = flat.reshape(n_states, n, k * 3)
    sq = np.ascontiguousarray(np.sum(flat ** 2, axis=-1).T)   # (F, S)
    by_frame = np.transpose(flat, (1, 0, 2))                  # (F, S, D)
    cross = by_frame[:-1] @ np.transpose(by_frame[1:], (0, 2, 1))
    # |a - b|^2 = |a|^2 + |b|^2 - 2 a.b for every pair of states of consecutive frames, summed in place
    # (the same numbers as one expression, in half the time: the (F, S, S) temporaries are the cost)
    pairwise = sq[:-1, :, None] + sq[1:, None, :]
    cross *= 2.0
    pairwise -= cross
    pairwise /= sigma_cont ** 2
    return _GroupStates(cand, vecs, unary, pairwise, flat)


def _group_prior(group, joints, pos, deps: list[int] | None = None) -> np.ndarray:
    """Unary prior cost (..., F) of a group's states given already placed parents: ``pos`` maps each of
    the group's joints to its places (..., F, 3), one leading index per state (or none for one state);
    ``joints`` (F, 17, 3) holds the parents.  With ``deps`` (:func:`_state_bits`, the leading index then
    being the state) the legs' terms are each worked out on the states of the bits they depend on (the
    hips' 4, a leg's 16) and spread to all 64: the same numbers."""
    j = JOINT_INDEX
    if group[0] == "l_hip":
        pel = joints[:, j["pelvis"]]

        def on(names):
            """``pos`` cut to the states of the bits the joints ``names`` depend on, and the spreading index."""
            if deps is None:
                return pos, slice(None)
            mask = 0
            for name in names:
                mask |= deps[group.index(name)]
            reps, expand = _sub_states(pos[j["l_hip"]].shape[0], mask)
            return {c: v[reps] for c, v in pos.items()}, expand

        hips, spread = on(("l_hip", "r_hip"))
        asym = (hips[j["l_hip"]] - pel) + (hips[j["r_hip"]] - pel)
        cost = (np.sum(asym ** 2, axis=-1) / SIGMA_SYMMETRY_M ** 2)[spread]
        for side in "lr":
            leg, spread = on(("l_hip", "r_hip", f"{side}_knee", f"{side}_ankle"))
            left = _left_axis(leg[j["l_hip"]], leg[j["r_hip"]])      # each state's own hips
            hip, knee, ankle = leg[j[f"{side}_hip"]], leg[j[f"{side}_knee"]], leg[j[f"{side}_ankle"]]
            cost = cost + ((hinge_violation(knee - hip, ankle - knee, left, 1.0) / SIGMA_KNEE) ** 2)[spread]
            cost = cost + _abduction_cost(knee - hip, ankle - hip, left)[spread]
        return cost
    if group[0] == "spine":
        return np.zeros(joints.shape[0])
    if group[0] in ("l_shoulder", "r_shoulder"):
        left, fwd = _body_axes(joints)
        side = group[0][0]
        sh, el, wr = pos[j[f"{side}_shoulder"]], pos[j[f"{side}_elbow"]], pos[j[f"{side}_wrist"]]
        cost = (hinge_violation(el - sh, wr - el, left, -1.0) / SIGMA_ELBOW) ** 2
        cost = cost + _abduction_cost(el - sh, wr - sh, left)
        # the clavicle points to its own side
        clav = sh - joints[:, j["thorax"]]
        lateral = np.sum(clav * left, axis=-1) * (1.0 if side == "l" else -1.0)
        cost = cost + (np.minimum(lateral, 0.0) / SIGMA_SYMMETRY_M) ** 2
        if SIGMA_ARM_SWING is not None:
            # walking and running swing each arm against its own leg: penalise the upper arm and the
            # same-side thigh pointing forward (or back) together, in proportion to both swings
            ua = el - sh
            th = joints[:, j[f"{side}_knee"]] - joints[:, j[f"{side}_hip"]]
            a = np.sum(ua * fwd, axis=-1) / np.maximum(np.linalg.norm(ua, axis=-1), 1e-9)
            b = np.sum(th * fwd, axis=-1) / np.maximum(np.linalg.norm(th, axis=-1), 1e-9)
            cost = cost + (np.maximum(a * b, 0.0) / SIGMA_ARM_SWING) ** 2
        if SIGMA_CLAVICLE_HIP is not None:
            # the shoulder line follows the hip line (the torso twists little): the clavicle's depth
            # sign should match its hip's; the arms' depth otherwise has no cue but the elbow
            hip = joints[:, j[f"{side}_hip"]] - joints[:, j["pelvis"]]
            du = (clav / np.maximum(np.linalg.norm(clav, axis=-1, keepdims=True), 1e-9)
                  - hip / np.maximum(np.linalg.norm(hip, axis=-1, keepdims=True), 1e-9))
            cost = cost + np.sum(du ** 2, axis=-1) / SIGMA_CLAVICLE_HIP ** 2
        return cost
    return np.zeros(joints.shape[0])


def _abduction_cost(upper: np.ndarray, whole: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Limbs mostly swing in the body's sagittal plane: penalise the sine of their sideways angle.

    Seen from the side a leg mirrored in depth keeps its knee bending the
    right way; only its sideways (abduction) angle tells the two apart.
    """
    cost = 0.0
    for v in (upper, whole):
        sine = np.sum(v * left, axis=-1) / np.maximum(np.linalg.norm(v, axis=-1), 1e-12)
        cost = cost + (sine / SIGMA_ABDUCTION) ** 2
    return cost
