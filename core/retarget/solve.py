"""Per-frame rotations of the target rig's bones that reproduce the source motion.

Why not copy local rotations: the target's rest pose differs (A-pose or T-pose, other bone rolls, other
proportions), so equal local rotations give a different pose.  Instead, in the target's armature space:

* The source is turned to face the way the rig faces (its rest pose says which way is left and up),
  scaled by the ratio of leg lengths, its feet put on the rig's floor and its first pelvis on the rig's
  hips (root motion starts where the character stands).
* **Body**: the hips take the source pelvis's rotation (hip line and spine) relative to its rest, the
  chest that of the shoulders and upper spine, the bones between blend the two (spherical
  interpolation); neck, head and clavicles turn as the source's do relative to the chest.
* **Limbs**: two-bone IK puts the ankles on the scaled source positions and the wrists where the
  source's are from its shoulders, scaled by the ratio of arm lengths (rigs differ in arm-to-leg
  proportion; this keeps the arm's pose and reach), with the knee and elbow in the source's bend
  plane; each limb bone is then swung, by the smallest rotation, from where its parent carries it
  to that direction (no twist of its own).  Feet stay level and turn with
  the body's heading; hands, toes, fingers and twist bones keep their rest relation to their parent.
* **Planted feet**: while a foot is in contact (the estimate's stance, or the source foot low and
  slow) its ankle target is held, on the ground plane, at the contact's mean position, blended in and
  out over a few frames; the hips drop where a leg could not reach.
* Rotations become each bone's local (basis) rotation: ``R = C_parent @ R_rest @ B``, with
  ``C_parent = R_parent @ R_parent_rest^T`` the parent's change from rest.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ..runs import runs as _runs
from ..skeleton import JOINT_INDEX
from .bone_map import SIDES, chain_between, check_bone_map
from .curves import sign_continuous
from .rig import TargetRig

_J = JOINT_INDEX
_X, _Z, _NEG_Y = np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, -1.0, 0])
#: The source's rest axes (left, up, forward) in its own world: left +X, up +Z, facing -Y.
SOURCE_REST = np.stack([_X, _Z, _NEG_Y], axis=1)


@dataclass
class RetargetSettings:
    plant_feet: bool = True
    #: Frames over which a planted foot blends in and out of its hold.
    blend_frames: int = 4
    #: Zero-phase low-pass of the source joints before retargeting, Hz (0: off).
    smooth_hz: float = 0.0
    ik_hands: bool = True
    #: A foot counts as in contact below this speed (source metres per second) ...
    contact_speed_m_s: float = 0.25
    #: ... and this height above its lowest positions (source metres).
    contact_height_m: float = 0.04
    #: Shortest contact kept, frames.
    min_contact_frames: int = 3
    #: A contact over which the source ankle wanders further than this from its mean is not a plant (m).
    contact_drift_m: float = 0.10


@dataclass
class RetargetResult:
    """``bones``: the keyed bones (names); ``rotation`` (F, k, 4) their local quaternions (w, x, y, z),
    sign-continuous; ``root`` the hips bone, ``root_location`` (F, 3) its local location; ``heads`` the
    posed heads (armature space) of every bone the solve placed, ``placed`` their names; ``scale``
    target units per source metre; ``targets`` (F, 4, 3) where ankles L/R and wrists L/R were asked to
    go (armature space), ``reached`` (F, 4, 3) where the rig's ankles and wrists went; ``contact`` (F, 2)
    the frames each foot was held."""

    bones: list[str]
    rotation: np.ndarray
    root: str
    root_location: np.ndarray
    placed: list[str]
    heads: np.ndarray
    scale: float
    targets: np.ndarray
    reached: np.ndarray
    contact: np.ndarray
    notes: list[str] = field(default_factory=list)
    #: (F, k, 3, 3) armature-space rotations of the keyed bones (for rigs baked by evaluation)
    world_rotation: np.ndarray | None = None

    @property
    def end_error(self) -> np.ndarray:
        """(F, 4) distance between where ankles and wrists were asked to go and where they went."""
        return np.linalg.norm(self.targets - self.reached, axis=-1)


# ----------------------------------------------------------------------------- small rotation helpers

def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, 1e-12)


def body_frame(left, up) -> np.ndarray:
    """(..., 3, 3) orthonormal frames with columns (left, up, forward), up kept exactly."""
    u = _unit(up)
    lt = _unit(left - np.sum(left * u, axis=-1, keepdims=True) * u)
    return np.stack([lt, u, np.cross(lt, u)], axis=-1)


def swing(a, b) -> np.ndarray:
    """(F, 3, 3) smallest rotations taking directions ``a`` to ``b`` (F, 3)."""
    a, b = _unit(a), _unit(b)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1)
    c = np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)
    angle = np.arctan2(s, c)
    # opposite directions: any axis perpendicular to a
    fallback = np.cross(a, np.where(np.abs(a[:, :1]) < 0.9, _X, np.array([0, 1.0, 0])))
    axis = np.where((s < 1e-9)[:, None] & (c < 0)[:, None], fallback, axis)
    rv = _unit(axis) * angle[:, None]
    rv[(s < 1e-9) & (c > 0)] = 0.0
    return Rotation.from_rotvec(rv).as_matrix()


def _slerp(r0, r1, t: float) -> np.ndarray:
    rel = Rotation.from_matrix(np.einsum("fji,fjk->fik", r0, r1)).as_rotvec()
    return r0 @ Rotation.from_rotvec(rel * t).as_matrix()


def _about(axis, angle) -> np.ndarray:
    return Rotation.from_rotvec(np.outer(angle, axis)).as_matrix()


def two_bone_ik(root, target, l1: float, l2: float, pole):
    """(mid, end) (F, 3): the middle joint and the end of a two-bone chain from ``root`` reaching for
    ``target``, bending toward ``pole`` (a direction); out-of-reach targets are approached in line."""
    v = target - root
    d = np.linalg.norm(v, axis=-1)
    u = _unit(v)
    d = np.clip(d, abs(l1 - l2) + 1e-6 * (l1 + l2), (l1 + l2) * (1.0 - 1e-6))
    p = pole - np.sum(pole * u, axis=-1, keepdims=True) * u
    p = _unit(p)
    cos_a = np.clip((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a * cos_a)
    mid = root + l1 * (cos_a[:, None] * u + sin_a[:, None] * p)
    return mid, root + u * d[:, None]


def _fill_degenerate(v, ok, fallback) -> np.ndarray:
    """Where ``ok`` is False, the last good value (or ``fallback`` before the first)."""
    out = v.copy()
    last = None
    for i in range(len(v)):
        if ok[i]:
            last = v[i]
        else:
            out[i] = last if last is not None else fallback[i]
    return out


# ----------------------------------------------------------------------------- source preparation

def smooth_joints(joints: np.ndarray, fps: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase 2nd-order Butterworth low-pass of every coordinate (unchanged when too short)."""
    if cutoff_hz <= 0 or fps <= 0 or cutoff_hz >= 0.5 * fps or len(joints) < 16:
        return joints
    from scipy.signal import butter, filtfilt

    b, a = butter(2, cutoff_hz / (0.5 * fps))
    return filtfilt(b, a, joints, axis=0)


def contact_masks(joints: np.ndarray, fps: float, stance, s: RetargetSettings) -> np.ndarray:
    """(F, 2) bool: left, right foot in contact.

    A foot is in contact when it is low and slow, or when the estimate says it stands on it and it is
    near the floor and not fast (an estimate's stance can be wrong where its motion is: a foot 30 cm up
    or sweeping forward is not planted, whatever the stance says).  Speeds are taken over 0.1 s, so
    the rate and the jitter of the footage do not decide.  A contact over which the foot travels more
    than ``contact_drift_m`` is dropped: holding it would drag the character's foot to a place the
    source foot never was."""
    n = len(joints)
    out = np.zeros((n, 2), dtype=bool)
    half = max(1, int(round(0.05 * fps)))
    lo_i, hi_i = np.maximum(np.arange(n) - half, 0), np.minimum(np.arange(n) + half, n - 1)
    dt = np.maximum(hi_i - lo_i, 1) / fps
    said = None if stance is None else np.asarray(list(stance)[:n] + [None] * max(0, n - len(stance)), dtype=object)
    for k, side in enumerate("lr"):
        ankle = joints[:, _J[f"{side}_ankle"]]
        speed = np.linalg.norm(ankle[hi_i] - ankle[lo_i], axis=1) / dt if n > 1 else np.zeros(n)
        height = ankle[:, 2] - np.percentile(ankle[:, 2], 5)
        mask = (height < s.contact_height_m) & (speed < s.contact_speed_m_s)
        if said is not None:
            mask |= ((said == side) & (height < 3 * s.contact_height_m) & (speed < 3 * s.contact_speed_m_s))
        for a, b in _runs(mask):
            drift = np.linalg.norm(ankle[a:b, :2] - ankle[a:b, :2].mean(axis=0), axis=1).max()
            if b - a < s.min_contact_frames or drift > s.contact_drift_m:
                mask[a:b] = False
        out[:, k] = mask
    return out


def _hold(free: np.ndarray, mask: np.ndarray, blend: int) -> np.ndarray:
    """``free`` (F, d) held at each contact run's mean, blended in and out over ``blend`` frames."""
    n = len(free)
    weight = np.zeros(n)
    held = free.copy()
    for a, b in _runs(mask):
        value = free[a:b].mean(axis=0)
        lo, hi = max(0, a - blend), min(n, b + blend)
        for i in range(lo, hi):
            if a <= i < b:
                w = 1.0
            else:
                gap = (a - i) if i < a else (i - b + 1)
                x = 1.0 - gap / (blend + 1.0)
                w = x * x * (3 - 2 * x)
            if w > weight[i]:
                weight[i] = w
                held[i] = value
    return weight[:, None] * held + (1 - weight[:, None]) * free


# ----------------------------------------------------------------------------- the solve

def _snap(v: np.ndarray, limit_deg: float = 15.0) -> np.ndarray:
    """``v`` (unit) turned onto the nearest armature axis when within ``limit_deg`` of it (rigs are built
    along their axes; a leaning spine or bent knee should not tilt the whole motion)."""
    k = int(np.argmax(np.abs(v)))
    axis = np.zeros(3)
    axis[k] = np.sign(v[k])
    return axis if np.degrees(np.arccos(np.clip(abs(v[k]), -1, 1))) <= limit_deg else v


def _rest_axes(rig: TargetRig, roles: dict) -> np.ndarray:
    """The rig's rest (left, up, forward) axes in armature space: up from the ankles to the hips (legs
    stand straighter than spines lean), left across hips and shoulders."""
    def ankle(side):
        return rig.head[roles[f"foot.{side}"]] if f"foot.{side}" in roles else rig.tail[roles[f"shin.{side}"]]

    left = rig.head[roles["thigh.L"]] - rig.head[roles["thigh.R"]]
    left = left + rig.head[roles["upper_arm.L"]] - rig.head[roles["upper_arm.R"]]
    up = 0.5 * (rig.head[roles["thigh.L"]] + rig.head[roles["thigh.R"]]) - 0.5 * (ankle("L") + ankle("R"))
    up = _snap(up / np.linalg.norm(up))
    left = left - (left @ up) * up
    left = _snap(left / np.linalg.norm(left))
    return body_frame(left[None], up[None])[0]


def _leg_length_rig(rig, roles, side):
    thigh, shin = roles[f"thigh.{side}"], roles[f"shin.{side}"]
    ankle = rig.head[roles[f"foot.{side}"]] if f"foot.{side}" in roles else rig.tail[shin]
    return float(np.linalg.norm(rig.head[shin] - rig.head[thigh]) + np.linalg.norm(ankle - rig.head[shin]))


def retarget(rig: TargetRig, bone_map: dict[str, str], joints: np.ndarray, *, fps: float = 30.0, stance=None,
             settings: RetargetSettings | None = None) -> RetargetResult:
    """Retarget source joints (F, 17, 3) (Z up, metres, finite) onto ``rig`` through ``bone_map``."""
    s = settings or RetargetSettings()
    roles = check_bone_map(rig, bone_map)
    joints = np.asarray(joints, dtype=float)
    if joints.ndim != 3 or joints.shape[1:] != (17, 3) or len(joints) == 0 or not np.isfinite(joints).all():
        raise ValueError("retarget needs finite source joints of shape (F, 17, 3)")
    n_frames = len(joints)
    joints = smooth_joints(joints, fps, s.smooth_hz)

    # --- the source in the rig's space: facing, scale, floor, start
    axes = _rest_axes(rig, roles)
    turn = axes @ SOURCE_REST.T                                  # source rest axes -> rig rest axes
    up = axes[:, 1]
    src_leg = np.median(np.concatenate([
        np.linalg.norm(joints[:, _J[f"{p}_knee"]] - joints[:, _J[f"{p}_hip"]], axis=-1)
        + np.linalg.norm(joints[:, _J[f"{p}_ankle"]] - joints[:, _J[f"{p}_knee"]], axis=-1) for p in "lr"]))
    k = 0.5 * (_leg_length_rig(rig, roles, "L") + _leg_length_rig(rig, roles, "R")) / float(src_leg)
    ankle_rest_up = np.mean([float((rig.head[roles[f"foot.{x}"]] if f"foot.{x}" in roles
                                    else rig.tail[roles[f"shin.{x}"]]) @ up) for x in SIDES])
    src_ankle_floor = float(np.percentile(joints[:, [_J["l_ankle"], _J["r_ankle"]], 2], 5))
    src = joints.copy()
    src[..., 2] -= src_ankle_floor
    tgt = k * (src @ turn.T)
    hips = roles["hips"]
    start = 0.5 * (tgt[0, _J["l_hip"]] + tgt[0, _J["r_hip"]])
    shift = 0.5 * (rig.head[roles["thigh.L"]] + rig.head[roles["thigh.R"]]) - start
    shift = shift - (shift @ up) * up + ankle_rest_up * up        # horizontal: start on the hips; up: floor
    tgt += shift

    contact = contact_masks(joints, fps, stance, s) if s.plant_feet else np.zeros((n_frames, 2), dtype=bool)
    ankles = np.stack([tgt[:, _J["l_ankle"]], tgt[:, _J["r_ankle"]]], axis=1)
    if s.plant_feet:       # held on the ground plane; the height follows the source (the heel rises at push-off)
        for kk in range(2):
            height = ankles[:, kk] @ up
            ankles[:, kk] = _hold(ankles[:, kk] - np.outer(height, up), contact[:, kk], s.blend_frames) \
                + np.outer(height, up)
    wrists = np.zeros((n_frames, 2, 3))            # filled by the arms' IK below

    # --- body rotations, in the source's world, then turned into the rig's space
    def delta(left, upv):
        return turn @ body_frame(left, upv) @ SOURCE_REST.T @ turn.T

    d_hips = delta(joints[:, _J["l_hip"]] - joints[:, _J["r_hip"]], joints[:, _J["spine"]] - joints[:, _J["pelvis"]])
    d_chest = delta(joints[:, _J["l_shoulder"]] - joints[:, _J["r_shoulder"]],
                    joints[:, _J["thorax"]] - joints[:, _J["spine"]])

    def seg(a, b):
        return _unit((joints[:, _J[b]] - joints[:, _J[a]]) @ turn.T)

    chest_up = np.einsum("fij,j->fi", d_chest, up)
    d_neck = swing(chest_up, seg("thorax", "neck")) @ d_chest
    d_head = swing(chest_up, seg("neck", "head")) @ d_chest
    d_clav = {}
    for side, sign in (("L", 1.0), ("R", -1.0)):
        rest_dir = np.einsum("fij,j->fi", d_chest, turn @ (sign * _X))
        d_clav[side] = swing(rest_dir, seg("thorax", f"{side.lower()}_shoulder")) @ d_chest
    fwd = axes[:, 2]
    yaw_fwd = np.einsum("fij,j->fi", d_hips, fwd)
    yaw_fwd = yaw_fwd - np.outer(yaw_fwd @ up, up)
    yaw = np.unwrap(np.arctan2(yaw_fwd @ np.cross(fwd, up) * -1.0, yaw_fwd @ fwd))
    yaw = smooth_joints(yaw[:, None], fps, 1.5)[:, 0] if n_frames >= 16 else yaw

    # --- which bones the solve places (mapped bones, their ancestors, the spine and neck chains)
    chest, head = roles["chest"], roles["head"]
    spine_chain = chain_between(rig, hips, chest)
    neck_chain = chain_between(rig, chest, head)
    role_of = {i: r for r, i in roles.items()}
    needed = set(roles.values()) | set(spine_chain) | set(neck_chain)
    for i in list(needed):
        needed.update(rig.ancestors(i))
    order = sorted(needed)
    keyed = [i for i in order if i in role_of or i in spine_chain or i in neck_chain]
    keyed = [i for i in keyed if role_of.get(i, "").split(".")[0] not in ("hand", "toe")]

    eye = np.broadcast_to(np.eye(3), (n_frames, 3, 3))
    rot: dict[int, np.ndarray] = {}
    pos: dict[int, np.ndarray] = {}
    ik_mid: dict[str, np.ndarray] = {}
    ik_end: dict[str, np.ndarray] = {}
    root_location = np.zeros((n_frames, 3))
    notes: list[str] = []

    def carried(i):
        p = int(rig.parents[i])
        return eye if p < 0 else rot[p] @ rig.rest[p].T

    def rigid_head(i):
        p = int(rig.parents[i])
        if p < 0:
            return np.broadcast_to(rig.head[i], (n_frames, 3)).copy()
        return pos[p] + np.einsum("fij,j->fi", carried(i), rig.head[i] - rig.head[p])

    def swung(i, toward):
        """The bone as its parent carries it, swung so its head-to-``toward`` runs along the target."""
        c = carried(i)
        rest_vec = toward[1] - rig.head[i]
        return swing(np.einsum("fij,j->fi", c, rest_vec), toward[0] - pos[i]) @ c @ rig.rest[i]

    def limb_end(side, part_lo, end_part):
        """Rest position of a limb's end: the head of its end bone (foot, hand) or its lower bone's tail."""
        lo = roles[f"{part_lo}.{side}"]
        return rig.head[roles[f"{end_part}.{side}"]] if f"{end_part}.{side}" in roles else rig.tail[lo]

    for i in order:
        role = role_of.get(i, "")
        c = carried(i)
        if i == hips:
            rot[i] = d_hips @ rig.rest[i]
            # anchored at the hip joints (where the legs start), not at the source's pelvis point, whose
            # height above them differs between skeletons
            mid_src = 0.5 * (tgt[:, _J["l_hip"]] + tgt[:, _J["r_hip"]])
            mid_rig = 0.5 * (rig.head[roles["thigh.L"]] + rig.head[roles["thigh.R"]])
            target_head = mid_src - np.einsum("fij,j->fi", d_hips, mid_rig - rig.head[hips])
            drop = np.zeros(n_frames)
            for kk, side in enumerate(SIDES):
                thigh = roles[f"thigh.{side}"]
                hip_pt = target_head + np.einsum("fij,j->fi", d_hips, rig.head[thigh] - rig.head[hips])
                reach = 0.999 * _leg_length_rig(rig, roles, side)
                v = ankles[:, kk] - hip_pt
                vu = v @ up
                disc = vu * vu - (np.sum(v * v, axis=1) - reach * reach)
                need = np.where(disc >= 0, -vu - np.sqrt(np.maximum(disc, 0)), -vu)
                drop = np.maximum(drop, np.where(np.sum(v * v, axis=1) > reach * reach, np.maximum(need, 0), 0))
            pos[i] = target_head - np.outer(drop, up)
            root_location = np.einsum("ji,fj->fi", rig.rest[i], np.einsum("fji,fj->fi", c, pos[i] - rigid_head(i)))
            low = drop > 0.005 * _leg_length_rig(rig, roles, "L")
            if low.any():
                notes.append(f"hips lowered on {int(low.sum())} frames so the feet reach the ground "
                             f"(up to {100 * drop.max() / _leg_length_rig(rig, roles, 'L'):.0f} % of a leg)")
            continue
        pos[i] = rigid_head(i)
        if i == chest:
            rot[i] = d_chest @ rig.rest[i]
        elif i in spine_chain:
            t = (spine_chain.index(i) + 1) / (len(spine_chain) + 1)
            rot[i] = _slerp(d_hips, d_chest, t) @ rig.rest[i]
        elif i in neck_chain:
            rot[i] = d_neck @ rig.rest[i]
        elif i == head:
            rot[i] = d_head @ rig.rest[i]
        elif role.startswith("clavicle."):
            rot[i] = d_clav[role[-1]] @ rig.rest[i]
        elif role.startswith(("upper_arm.", "thigh.")):
            side = role[-1]
            leg = role.startswith("thigh.")
            lo_part, end_part = ("shin", "foot") if leg else ("forearm", "hand")
            lo = roles[f"{lo_part}.{side}"]
            end_rest = limb_end(side, lo_part, end_part)
            l1 = float(np.linalg.norm(rig.head[lo] - rig.head[i]))
            l2 = float(np.linalg.norm(end_rest - rig.head[lo]))
            a, m, e = (("hip", "knee", "ankle") if leg else ("shoulder", "elbow", "wrist"))
            sj = side.lower()
            if leg:
                goal = ankles[:, 0 if side == "L" else 1]
            elif s.ik_hands:       # where the source's hand is from its shoulder, scaled by the arms' lengths
                sh, el, wr = (joints[:, _J[f"{sj}_{n}"]] for n in ("shoulder", "elbow", "wrist"))
                reach = wr - sh
                src_arm = np.median(np.linalg.norm(el - sh, axis=1) + np.linalg.norm(wr - el, axis=1))
                goal = pos[i] + (l1 + l2) / float(src_arm) * (reach @ turn.T)
            else:
                goal = pos[i] + (l1 + l2) * _unit(seg(f"{sj}_{a}", f"{sj}_{e}"))
            if not leg:
                wrists[:, 0 if side == "L" else 1] = goal
            axis = joints[:, _J[f"{sj}_{e}"]] - joints[:, _J[f"{sj}_{a}"]]
            bend = joints[:, _J[f"{sj}_{m}"]] - joints[:, _J[f"{sj}_{a}"]]
            pole = bend - np.sum(bend * _unit(axis), axis=1, keepdims=True) * _unit(axis)
            ok = np.linalg.norm(pole, axis=1) > 0.02 * float(np.median(np.linalg.norm(axis, axis=1)) + 1e-9)
            pole = pole @ turn.T
            body = d_hips if leg else d_chest
            default = np.einsum("fij,j->fi", body, fwd if leg else -fwd)
            pole = _fill_degenerate(pole, ok, default)
            mid, end = two_bone_ik(pos[i], goal, l1, l2, pole)
            ik_mid[f"{role}"], ik_end[f"{role}"] = mid, end
            rot[i] = swung(i, (mid, rig.head[lo]))
        elif role.startswith(("forearm.", "shin.")):
            side = role[-1]
            hi_role = ("thigh." if role.startswith("shin.") else "upper_arm.") + side
            end_part = "foot" if role.startswith("shin.") else "hand"
            end_rest = limb_end(side, role.split(".")[0], end_part)
            rot[i] = swung(i, (ik_end[hi_role], end_rest))
        elif role.startswith("foot."):
            side = role[-1]
            foot_yaw = yaw
            if s.plant_feet:
                foot_yaw = _hold(yaw[:, None], contact[:, 0 if side == "L" else 1], s.blend_frames)[:, 0]
            rot[i] = _about(up, foot_yaw) @ rig.rest[i]
        else:
            rot[i] = c @ rig.rest[i]          # rigid with its parent (hands, toes, helpers on the way)

    # --- local rotations of the keyed bones, sign-continuous quaternions (w, x, y, z)
    quats = np.empty((n_frames, len(keyed), 4))
    for col, i in enumerate(keyed):
        basis = np.einsum("ji,fjk->fik", rig.rest[i], np.einsum("fji,fjk->fik", carried(i), rot[i]))
        q = sign_continuous(Rotation.from_matrix(basis).as_quat()[:, [3, 0, 1, 2]])
        quats[:, col] = -q if q[0, 0] < 0 else q

    ends = []
    for side in SIDES:
        shin = roles[f"shin.{side}"]
        ends.append(pos[shin] + np.einsum("fij,j->fi", rot[shin] @ rig.rest[shin].T,
                                          limb_end(side, "shin", "foot") - rig.head[shin]))
    for side in SIDES:
        fa = roles[f"forearm.{side}"]
        ends.append(pos[fa] + np.einsum("fij,j->fi", rot[fa] @ rig.rest[fa].T,
                                        limb_end(side, "forearm", "hand") - rig.head[fa]))
    targets = np.stack([ankles[:, 0], ankles[:, 1], wrists[:, 0], wrists[:, 1]], axis=1)
    reached = np.stack(ends, axis=1)
    placed = [rig.names[i] for i in order]
    heads = np.stack([pos[i] for i in order], axis=1)
    world = np.stack([rot[i] for i in keyed], axis=1)
    return RetargetResult([rig.names[i] for i in keyed], quats, rig.names[hips], root_location, placed, heads,
                          float(k), targets, reached, contact, notes, world)
