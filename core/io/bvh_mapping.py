"""Map any BVH skeleton onto the canonical 17 joints by the shape of its chains.

Why by shape: every mocap source names its joints differently (CMU
``LeftUpLeg`` or ``LeftHip``, Bandai ``UpperLeg_L``, Poser ``lThigh``,
Mixamo ``mixamorig:LeftUpLeg`` ...), but every human skeleton has the same
tree shape: two long leaf-ward chains (legs) leave the hips, an upper body
with two long chains (arms) and an upward chain (neck and head) leaves the
spine.  Names are used to tell left from right, and to find the hands and
feet where a chain names them.

How (all geometry from the *posed* frames, because some files, e.g. Bandai
Namco, have a meaningless rest pose; bone lengths are medians over sampled
frames):

* **pelvis** = the hub: the first node, from the root down, with more than
  one child (so a ``joint_Root`` on the floor above ``Hips`` is skipped).
* The hub's child subtree with the most leaves is the **upper body**; every
  other child subtree is a **leg** (a child subtree that itself splits into
  two long branches, e.g. ``Hips -> Pelvis -> {LThigh, RThigh}``, gives two
  legs).  Fewer or more than two legs is an :class:`InputError` ("no second
  leg chain found").
* A limb chain is the path from its attachment (hub or thorax) to its
  farthest leaf, with coincident nodes merged (zero offsets such as CMU's
  ``LHipJoint`` or ``LeftFingerBase``).  The **end joint** (ankle, wrist) is
  the first node, after at least two bones, named a foot or ankle (a hand or
  wrist) where the chain names one; otherwise the first node after at least
  two bones whose remaining distal length (foot + toes, hand + fingers) is
  under 0.7 of the bone that reaches it (Character Creator's hand, with three
  finger joints, is longer than that: by shape alone its fingers pass for the
  wrist); the two nodes before it are **knee/elbow** and **hip/shoulder** (the thigh or
  upper-arm root).  Whatever lies between the attachment and that root is
  the canonical ``hip``/``clavicle`` segment.  (The two longest bones are
  *not* a safe rule: in CMU files the clavicle is longer than the forearm.)
* **thorax** = the first node up the spine where at least three long chains
  branch (the two arms and the neck).  Of its children the most upward is
  the head chain, the two longest others are the arms.
* **neck** = the first node of the head chain not coincident with the thorax
  (CMU's ``Neck`` sits on ``Spine1``, so ``Neck1`` is used).
* **head** = the head top: the End Site that ends the head chain when it has
  a real length; otherwise (Bandai's zero End Site, Poser's eye joints) a
  point fixed in the head joint's frame, along the direction of the bone
  that reaches the head joint, 0.2 of a leg length beyond it.
* **spine** = the lowest spine node between pelvis and thorax that lies
  between 0.15 and 0.65 of the pelvis-to-neck chain length (typically near
  1/3); with none there (SFU's ``Spine`` sits on the hips) a virtual point
  at 1/3 of the chain on the straight pelvis-thorax line.
* **left/right**: by names when they decide (``Left*``, ``l*``, ``*_L``,
  ``*.l`` ...); otherwise geometrically: forward is the toe direction (or
  the knee's bend), up is pelvis to thorax, and left is ``up x forward``
  (right-handed axes, as BVH files use), taken from the rest pose when it
  is an upright, clear T/A-pose and otherwise voted over sampled frames.
  Arms without deciding names take the side of the hip they are nearest to.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..skeleton import JOINTS
from .bvh import Bvh

#: Hand/foot shorter than this fraction of the forearm/shank marks the wrist/ankle (where no name does).
END_JOINT_RATIO = 0.7
#: A limb chain's node named so is its wrist or ankle: the first such node from the body outwards (Mixamo's
#: finger joints, ``LeftHandIndex1``, come after ``LeftHand``). Twist and roll bones are named after the
#: bone they lie along (``ForearmTwist``), not after the hand.
END_NAMES = {"arm": re.compile(r"hand|wrist", re.IGNORECASE), "leg": re.compile(r"foot|ankle", re.IGNORECASE)}
#: Head top beyond the head joint when the file has no head-top End Site, per leg length.
HEAD_TOP_PER_LEG = 0.2
#: The canonical spine joint is the lowest spine node within this fraction range of the
#: pelvis-to-neck chain; without one, a virtual point at ``SPINE_FRACTION``.
SPINE_RANGE = (0.15, 0.65)
SPINE_FRACTION = 1.0 / 3.0
_SAMPLE_FRAMES = 24


@dataclass(frozen=True)
class CanonicalPoint:
    """Where a canonical joint is on the BVH skeleton.

    ``joint`` plus ``offset`` in that node's local frame (non-zero only for a
    synthesised head top), optionally blended towards node ``toward`` by
    ``t`` (a virtual spine point).
    """

    joint: int
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    toward: int = -1
    t: float = 0.0


@dataclass
class CanonicalMapping:
    """The result of mapping: nearest BVH node and exact point per canonical joint."""

    indices: dict[str, int]
    points: dict[str, CanonicalPoint]
    notes: list[str] = field(default_factory=list)

    def names(self, bvh: Bvh) -> dict[str, str]:
        """Canonical name -> BVH node name (for reports)."""
        return {k: bvh.names[v] for k, v in self.indices.items()}


def map_to_canonical(bvh: Bvh) -> dict[str, int]:
    """Canonical joint name -> BVH node index (see :func:`build_mapping`)."""
    return build_mapping(bvh).indices


def canonical_positions(bvh: Bvh, mapping: CanonicalMapping | None = None, frames=None) -> np.ndarray:
    """The 17 canonical joints (F, 17, 3) in the file's units and axes."""
    mapping = build_mapping(bvh) if mapping is None else mapping
    positions, rotations = bvh.world_transforms(frames)
    out = np.empty((positions.shape[0], len(JOINTS), 3))
    for k, name in enumerate(JOINTS):
        point = mapping.points[name]
        p = positions[:, point.joint]
        if point.toward >= 0:
            p = (1.0 - point.t) * p + point.t * positions[:, point.toward]
        if any(point.offset):
            p = p + rotations[:, point.joint] @ np.asarray(point.offset)
        out[:, k] = p
    return out


# --------------------------------------------------------------------------- mapping


class _Geometry:
    """Posed positions on sampled frames and median bone lengths."""

    def __init__(self, bvh: Bvh):
        n = bvh.n_frames
        frames = np.unique(np.linspace(0, n - 1, min(n, _SAMPLE_FRAMES)).round().astype(int))
        self.positions = bvh.world_positions(frames)                     # (S, J, 3)
        bone = np.zeros(bvh.n_joints)
        for j, p in enumerate(bvh.parents):
            if p >= 0:
                bone[j] = np.median(np.linalg.norm(self.positions[:, j] - self.positions[:, p], axis=-1))
        self.bone = bone                                                  # length of the bone reaching j
        self.size = float(max(bone.sum(), 1e-12))
        self.eps = 1e-5 * self.size
        self.distal = np.zeros(bvh.n_joints)                              # longest path j -> leaf
        for j in range(bvh.n_joints - 1, -1, -1):                         # children follow parents
            kids = bvh.children[j]
            if kids:
                self.distal[j] = max(self.bone[c] + self.distal[c] for c in kids)


def build_mapping(bvh: Bvh) -> CanonicalMapping:
    """Map ``bvh`` to the canonical joints; :class:`InputError` naming what is missing."""
    geo = _Geometry(bvh)
    where = bvh.path
    hub = 0
    while len(bvh.children[hub]) == 1:
        hub = bvh.children[hub][0]
    if not bvh.children[hub]:
        raise InputError(f"{where}: the skeleton is a single chain; no hips with legs and a spine found")
    subtrees = {c: _leaves(bvh, c) for c in bvh.children[hub]}
    upper = max(subtrees, key=lambda c: (len(subtrees[c]), geo.distal[c] + geo.bone[c]))
    if len(subtrees[upper]) < 3:
        raise InputError(f"{where}: no upper body (spine with two arms and a head) found below {bvh.names[hub]!r}")

    legs = _leg_roots(bvh, geo, hub, [c for c in subtrees if c != upper])
    if not legs:
        raise InputError(f"{where}: no leg chains found below {bvh.names[hub]!r}")
    if len(legs) == 1:
        raise InputError(f"{where}: no second leg chain found below {bvh.names[hub]!r} "
                         f"(only {bvh.names[legs[0]]!r})")
    if len(legs) > 2:
        raise InputError(f"{where}: more than two leg chains below {bvh.names[hub]!r}: "
                         + ", ".join(bvh.names[c] for c in legs))
    leg_joints = [_limb_joints(bvh, geo, hub, c, "leg") for c in legs]

    leg_length = float(np.mean([_dist(geo, h, k) + _dist(geo, k, a) for h, k, a in leg_joints]))
    long_chain = 0.2 * leg_length
    thorax, spine_path = _find_thorax(bvh, geo, upper, long_chain)
    head_root, arm_roots = _split_thorax(bvh, geo, hub, thorax, long_chain)
    arm_joints = [_limb_joints(bvh, geo, thorax, c, "arm") for c in arm_roots]

    neck_path = [head_root] + _single_child_path(bvh, head_root)
    neck = next((j for j in neck_path if _dist(geo, j, thorax) > geo.eps), None)
    if neck is None:
        raise InputError(f"{where}: the head chain above {bvh.names[thorax]!r} has no length (no neck found)")
    head_point = _head_top(bvh, geo, neck, leg_length)

    spine_point = _spine_point(bvh, geo, hub, thorax, neck, spine_path)

    legs_lr, leg_note = _order_left_right(bvh, geo, legs, leg_joints, hub, thorax, kind="leg")
    arms_lr, arm_note = _order_arms(bvh, geo, arm_roots, arm_joints, legs_lr, leg_joints, legs, hub, thorax)

    points: dict[str, CanonicalPoint] = {
        "pelvis": CanonicalPoint(hub), "spine": spine_point, "thorax": CanonicalPoint(thorax),
        "neck": CanonicalPoint(neck), "head": head_point,
    }
    for side, leg in zip("lr", legs_lr, strict=True):
        hip, knee, ankle = leg_joints[legs.index(leg)]
        points.update({f"{side}_hip": CanonicalPoint(hip), f"{side}_knee": CanonicalPoint(knee),
                       f"{side}_ankle": CanonicalPoint(ankle)})
    for side, arm in zip("lr", arms_lr, strict=True):
        shoulder, elbow, wrist = arm_joints[arm_roots.index(arm)]
        points.update({f"{side}_shoulder": CanonicalPoint(shoulder), f"{side}_elbow": CanonicalPoint(elbow),
                       f"{side}_wrist": CanonicalPoint(wrist)})
    indices = {}
    for name in JOINTS:
        point = points[name]
        indices[name] = point.toward if point.toward >= 0 and point.t > 0.5 else point.joint
    notes = [leg_note, arm_note]
    if any(head_point.offset):
        notes.append(f"head top synthesised beyond {bvh.names[head_point.joint]!r}")
    if spine_point.toward >= 0:
        notes.append("spine is a virtual point between pelvis and thorax")
    return CanonicalMapping(indices, points, notes)


def _leaves(bvh: Bvh, j: int) -> list[int]:
    out, stack = [], [j]
    while stack:
        k = stack.pop()
        if bvh.children[k]:
            stack.extend(bvh.children[k])
        else:
            out.append(k)
    return out


def _dist(geo: _Geometry, a: int, b: int) -> float:
    return float(np.median(np.linalg.norm(geo.positions[:, a] - geo.positions[:, b], axis=-1)))


def _single_child_path(bvh: Bvh, j: int) -> list[int]:
    """Nodes below ``j`` while each has exactly one child."""
    out = []
    while len(bvh.children[j]) == 1:
        j = bvh.children[j][0]
        out.append(j)
    return out


def _leg_roots(bvh: Bvh, geo: _Geometry, hub: int, candidates: list[int]) -> list[int]:
    """Leg chains among the hub's non-upper-body children (splitting a shared pelvis node)."""
    legs = []
    for c in candidates:
        split = c
        while len(bvh.children[split]) == 1:
            split = bvh.children[split][0]
        kids = bvh.children[split]
        long_kids = [k for k in kids if geo.bone[k] + geo.distal[k] > 0.3 * (geo.distal[c] + geo.bone[c])]
        if split != c or len(kids) >= 2:
            if len(long_kids) >= 2:
                legs.extend(long_kids)
                continue
        legs.append(c)
    if not legs:
        return legs
    reach = {c: _path_length_to_hub(bvh, geo, c, hub) + geo.distal[c] for c in legs}
    longest = max(reach.values())
    return [c for c in legs if reach[c] > 0.4 * longest]


def _path_length_to_hub(bvh: Bvh, geo: _Geometry, j: int, hub: int) -> float:
    total = 0.0
    while j != hub and j >= 0:
        total += geo.bone[j]
        j = int(bvh.parents[j])
    return total


def _chain_to_farthest_leaf(bvh: Bvh, geo: _Geometry, start: int) -> list[int]:
    chain = [start]
    j = start
    while bvh.children[j]:
        j = max(bvh.children[j], key=lambda c: geo.bone[c] + geo.distal[c])
        chain.append(j)
    return chain


def _limb_joints(bvh: Bvh, geo: _Geometry, attach: int, first: int, kind: str) -> tuple[int, int, int]:
    """(root, middle, end) nodes of a leg or arm: hip/knee/ankle or shoulder/elbow/wrist."""
    path = []
    j = int(bvh.parents[first])
    while j != attach and j >= 0:  # nodes between the attachment and the limb's first node (split pelvis)
        path.append(j)
        j = int(bvh.parents[j])
    chain = [attach] + path[::-1] + _chain_to_farthest_leaf(bvh, geo, first)
    groups: list[list[int]] = [[chain[0]]]
    for node in chain[1:]:
        if geo.bone[node] <= geo.eps:
            groups[-1].append(node)
        else:
            groups.append([node])
    # groups[0] holds the attachment (and nodes coincident with it)
    what = {"leg": ("hip", "knee", "ankle"), "arm": ("shoulder", "elbow", "wrist")}[kind]
    if len(groups) < 4:
        raise InputError(f"{bvh.path}: the {kind} chain from {bvh.names[first]!r} is too short to hold "
                         f"{', '.join(what)}")
    # by name where the chain names its hand or foot: a long hand (Character Creator's, with three finger
    # joints) is more than END_JOINT_RATIO of the forearm, and the shape alone then takes a finger for the wrist
    end = next((k for k in range(3, len(groups)) if any(END_NAMES[kind].search(bvh.names[n]) for n in groups[k])),
               None)
    if end is None:
        for k in range(3, len(groups)):
            reaching_bone = geo.bone[groups[k][0]]
            if geo.distal[groups[k][-1]] < END_JOINT_RATIO * reaching_bone:
                end = k
                break
    if end is None:
        end = len(groups) - 1
    return groups[end - 2][0], groups[end - 1][0], groups[end][0]


def _find_thorax(bvh: Bvh, geo: _Geometry, upper: int, long_chain: float) -> tuple[int, list[int]]:
    """The node where the arms and the neck branch, and the spine nodes below it."""
    path = []
    j = upper
    while True:
        kids = bvh.children[j]
        long_kids = [k for k in kids if geo.bone[k] + geo.distal[k] > long_chain]
        if len(long_kids) >= 3:
            return j, path
        if not kids:
            raise InputError(f"{bvh.path}: no arms found: the spine from {bvh.names[upper]!r} never branches "
                             "into two arms and a neck")
        path.append(j)
        j = max(kids, key=lambda c: len(_leaves(bvh, c)))


def _split_thorax(bvh: Bvh, geo: _Geometry, hub: int, thorax: int, long_chain: float) -> tuple[int, list[int]]:
    kids = [k for k in bvh.children[thorax] if geo.bone[k] + geo.distal[k] > long_chain]
    up = geo.positions[:, thorax] - geo.positions[:, hub]
    up /= np.maximum(np.linalg.norm(up, axis=-1, keepdims=True), 1e-12)

    def upwardness(k: int) -> float:
        leaf_pos = geo.positions[:, _chain_to_farthest_leaf(bvh, geo, k)[-1]]
        d = leaf_pos - geo.positions[:, thorax]
        d /= np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-12)
        return float(np.median(np.sum(d * up, axis=-1)))

    head = max(kids, key=upwardness)
    arms = sorted((k for k in kids if k != head), key=lambda c: geo.bone[c] + geo.distal[c], reverse=True)[:2]
    return head, arms


def _head_top(bvh: Bvh, geo: _Geometry, neck: int, leg_length: float) -> CanonicalPoint:
    j = neck
    while len(bvh.children[j]) == 1:
        j = bvh.children[j][0]
    real_end = geo.bone[j] > 0.05 * leg_length
    if not bvh.children[j] and bvh.is_end_site[j] and real_end and j != neck:
        return CanonicalPoint(j)                       # a real head-top End Site
    # zero-length End Site: extend its joint; a leaf joint without End Site: extend it;
    # a branching head (eye joints): extend the branching node
    head = int(bvh.parents[j]) if (bvh.is_end_site[j] and not real_end) else j
    # the bone reaching the head joint, in the head joint's own frame (all frames agree at zero rotation)
    local = _local_translation(bvh, head)
    if np.linalg.norm(local) < 1e-12:
        local = np.array([0.0, 1.0, 0.0])
    local = local / np.linalg.norm(local)
    return CanonicalPoint(head, tuple(float(v) for v in local * HEAD_TOP_PER_LEG * leg_length))


def _local_translation(bvh: Bvh, j: int) -> np.ndarray:
    """Node ``j``'s translation from its parent at frame 0 (position channels win over OFFSET)."""
    names = bvh.channels[j]
    if any(n.endswith("position") for n in names):
        out = np.zeros(3)
        for k, n in enumerate(names):
            if n.endswith("position"):
                out["xyz".index(n[0])] = bvh.motion[0, bvh.channel_start[j] + k]
        return out
    return np.array(bvh.offsets[j], dtype=float)


def _spine_point(bvh: Bvh, geo: _Geometry, hub: int, thorax: int, neck: int,
                 spine_path: list[int]) -> CanonicalPoint:
    to_thorax = _path_length_to_hub(bvh, geo, thorax, hub)
    total = to_thorax + _dist(geo, thorax, neck)
    best = None
    for j in spine_path:                                   # lowest first
        if _dist(geo, j, hub) <= geo.eps or _dist(geo, j, thorax) <= geo.eps:
            continue
        fraction = _path_length_to_hub(bvh, geo, j, hub) / total
        if SPINE_RANGE[0] <= fraction <= SPINE_RANGE[1]:
            best = j
            break
    if best is not None:
        return CanonicalPoint(best)
    t = float(np.clip(SPINE_FRACTION * total / max(to_thorax, 1e-12), 0.2, 0.8))
    return CanonicalPoint(hub, toward=thorax, t=t)


# --------------------------------------------------------------------------- left / right

_LEFT = re.compile(r"(left|^l(?=[A-Z_.\-\s\d])|[_.\-\s]l$|[a-z\d]L$|^l$)", re.IGNORECASE)
_RIGHT = re.compile(r"(right|^r(?=[A-Z_.\-\s\d])|[_.\-\s]r$|[a-z\d]R$|^r$)", re.IGNORECASE)


def side_from_name(name: str) -> int:
    """+1 if the name says left, -1 if right, 0 if it does not tell.

    Prefixes like ``mixamorig:`` are dropped.  ``lThigh``/``LHipJoint`` count
    as left (a lone ``l`` before a capital, digit or separator), ``lowerback``
    does not; ``UpperLeg_L``, ``hand.l`` and ``ShoulderL`` count as left, and so does a lone ``L``
    between separators (Character Creator's ``CC_Base_L_Thigh``).
    """
    base = name.rsplit(":", 1)[-1].rsplit("|", 1)[-1]
    lower = base.lower()
    if "left" in lower and "right" not in lower:
        return 1
    if "right" in lower and "left" not in lower:
        return -1
    left = bool(re.match(r"^[lL](?=[A-Z_.\-\s\d])", base) or re.search(r"[_.\-\s][lL]$", base)
                or re.search(r"[a-z\d]L$", base) or re.search(r"[_.][lL][_.]", base))
    right = bool(re.match(r"^[rR](?=[A-Z_.\-\s\d])", base) or re.search(r"[_.\-\s][rR]$", base)
                 or re.search(r"[a-z\d]R$", base) or re.search(r"[_.][rR][_.]", base))
    return int(left) - int(right)


def _name_vote(bvh: Bvh, root: int) -> int:
    votes = sum(side_from_name(bvh.names[j]) for j in _chain_nodes(bvh, root))
    return int(np.sign(votes))


def _chain_nodes(bvh: Bvh, root: int) -> list[int]:
    out, stack = [], [root]
    while stack:
        k = stack.pop()
        if not bvh.is_end_site[k]:
            out.append(k)
        stack.extend(bvh.children[k])
    return out


def _order_left_right(bvh: Bvh, geo: _Geometry, legs: list[int], leg_joints, hub: int, thorax: int,
                      kind: str) -> tuple[list[int], str]:
    votes = [_name_vote(bvh, c) for c in legs]
    if votes[0] != 0 and votes[0] == -votes[1]:
        order = legs if votes[0] > 0 else legs[::-1]
        return order, f"{kind}s: left/right from names"
    def score(p: np.ndarray) -> tuple[float, float]:
        up = p[:, thorax] - p[:, hub]
        forward = np.zeros_like(up)
        for hip, knee, ankle in leg_joints:
            toe = _chain_to_farthest_leaf(bvh, geo, ankle)[-1]
            if _dist(geo, toe, ankle) > geo.eps * 100:
                forward += p[:, toe] - p[:, ankle]
            else:
                forward += p[:, knee] - 0.5 * (p[:, hip] + p[:, ankle])
        return _agreement(p[:, leg_joints[0][0]] - p[:, leg_joints[1][0]], np.cross(up, forward))

    sign, note = _decide(score, bvh, geo, hub, thorax)
    order = legs if sign >= 0 else legs[::-1]
    return order, f"{kind}s: left/right from {note} geometry (toes forward, left = up x forward)"


def _agreement(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Sign vote of dot(a, b) over frames and the median |cosine| (how clear the vote is)."""
    dot = np.sum(a * b, axis=-1)
    norms = np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    cosine = np.abs(dot) / np.maximum(norms, 1e-300)
    return float(np.sign(dot).sum()), float(np.median(cosine))


def _decide(score, bvh: Bvh, geo: _Geometry, hub: int, thorax: int) -> tuple[float, str]:
    """Prefer the rest pose when it is an upright T/A-pose and clear, else vote over the sampled frames.

    Why: some captures have odd root rotations on their frames (milad), while
    a garbage rest pose (Bandai, LaFAN1: bones along +X) is never upright
    like the posed frames, so it is not trusted.
    """
    rest = bvh.rest_positions()[None]
    rest_up = rest[0, thorax] - rest[0, hub]
    posed_up = np.median(geo.positions[:, thorax] - geo.positions[:, hub], axis=0)
    cosine = float(rest_up @ posed_up) / max(float(np.linalg.norm(rest_up) * np.linalg.norm(posed_up)), 1e-300)
    if cosine > 0.7:
        rest_vote, rest_clarity = score(rest)
        if rest_clarity > 0.5:
            return rest_vote, "rest-pose"
    vote, _ = score(geo.positions)
    return vote, "posed"


def _order_arms(bvh: Bvh, geo: _Geometry, arms: list[int], arm_joints, legs_lr: list[int], leg_joints,
                legs: list[int], hub: int, thorax: int) -> tuple[list[int], str]:
    votes = [_name_vote(bvh, c) for c in arms]
    if votes[0] != 0 and votes[0] == -votes[1]:
        return (arms if votes[0] > 0 else arms[::-1]), "arms: left/right from names"
    l_hip = leg_joints[legs.index(legs_lr[0])][0]
    r_hip = leg_joints[legs.index(legs_lr[1])][0]

    def arm_score(p: np.ndarray) -> tuple[float, float]:
        return _agreement(p[:, arm_joints[0][0]] - p[:, arm_joints[1][0]], p[:, l_hip] - p[:, r_hip])

    score, _ = _decide(arm_score, bvh, geo, hub, thorax)
    return (arms if score >= 0 else arms[::-1]), "arms: left/right from the side of the hips"
