"""Baking onto rigs whose controls hang from constraint-driven mechanism bones (a generated Rigify rig).

There a control's local rotation depends on what the constraints of the bones above it do, so it
cannot be read off rest poses.  Most such chains still move rigidly: in Rigify the FK thigh hangs from
a mechanism bone that copies the hips' transform, so its pose is always ``hips @ C @ basis`` for one
constant ``C``.  :func:`rigid_relations` finds, for every keyed control, the nearest mapped ancestor
(or the armature) it keeps such a constant relation to, by posing the rig a few random ways and
evaluating it; those controls are then solved for every frame at once, in numpy.  Controls that blend
between two others (Rigify's neck at ``neck_follow`` 0.5) have no such relation: they alone are set
frame by frame (``pose_bone.matrix``) with the rig evaluated once per frame.  Sample frames are then
evaluated and compared with what the solve asked for; if they disagree the whole clip is baked by
evaluation, level by level, which is exact for any rig.
Rigify's limbs are switched to FK (their ``IK_FK`` property keyed to 1) when FK controls are mapped.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix
from scipy.spatial.transform import Rotation

from ...core.retarget.curves import sign_continuous
from .. import compat
from .keys import baking, key_location, key_rotation

#: Largest disagreement (degrees) between the baked pose and the solve on the check frames.
CHECK_DEG = 0.05
#: Random poses tried when looking for constant relations.
PROBES = 3


def _ancestors(name: str, parents: dict[str, str | None]) -> list[str]:
    out, p = [], parents.get(name)
    while p is not None:
        out.append(p)
        p = parents.get(p)
    return out


def _levels(names: list[str], parents: dict[str, str | None]) -> list[list[str]]:
    """``names`` grouped by depth below their root, shallowest first."""
    depth = {n: len(_ancestors(n, parents)) for n in names}
    return [[n for n in names if depth[n] == k] for k in range(max(depth.values()) + 1)]


def _mat(m) -> np.ndarray:
    return np.array([list(row) for row in m], dtype=float)


def rigid_relations(obj, keyed: list[str], parents: dict[str, str | None], root: str, *,
                    probes: int = PROBES, seed: int = 0) -> dict[str, tuple[str | None, np.ndarray]]:
    """For each keyed bone that has one: (anchor, C) with ``pose(bone) = pose(anchor) @ C @ basis(bone)``
    in every pose, ``anchor`` its nearest mapped ancestor that gives a constant ``C`` (None: the armature
    itself, ``pose = C @ basis``).  Only rotations are keyed below the root, so only the rotation part
    must be constant there; the root's location is keyed too and its whole ``C`` must be.  Found by
    evaluating the rig at rest and in ``probes`` random poses of all keyed bones together (the root
    moved as well); the rig's pose is put back afterwards.  Bones missing from the result move with
    more than one other bone (a blend) and must be set by evaluation."""
    rng = np.random.default_rng(seed)
    saved = {b: obj.pose.bones[b].matrix_basis.copy() for b in keyed}
    layer = bpy.context.view_layer
    lengths = [obj.data.bones[b].length for b in keyed]
    unit = max(lengths) if lengths else 1.0
    samples = []
    try:
        for k in range(probes + 1):
            basis = {}
            for b in keyed:
                m = np.eye(4)
                if k:
                    m[:3, :3] = Rotation.from_rotvec(rng.normal(size=3) * 0.6).as_matrix()
                if k and b == root:
                    m[:3, 3] = rng.normal(size=3) * 0.1 * unit
                elif b != root:
                    m[:3, 3] = saved[b].translation
                obj.pose.bones[b].matrix_basis = Matrix(m.tolist())
                basis[b] = _mat(obj.pose.bones[b].matrix_basis)        # as Blender stored it
            layer.update()
            samples.append((basis, {b: _mat(obj.pose.bones[b].matrix) for b in keyed}))
    finally:
        for b, m in saved.items():
            obj.pose.bones[b].matrix_basis = m
        layer.update()

    out = {}
    for b in keyed:
        for anchor in [a for a in _ancestors(b, parents) if a in saved] + [None]:
            cs = [(np.linalg.inv(pose[anchor]) if anchor else np.eye(4)) @ pose[b] @ np.linalg.inv(basis[b])
                  for basis, pose in samples]
            rot = cs[0][:3, :3]
            if (max(np.abs(c[:3, :3] - rot).max() for c in cs) < 1e-4
                    and (b != root or max(np.abs(c[:3, 3] - cs[0][:3, 3]).max() for c in cs) < 1e-4 * unit)
                    and np.abs(rot.T @ rot - np.eye(3)).max() < 1e-4):       # no scale: a pure rotation
                out[b] = (anchor, cs[0])
                break
    return out


def _quat_wxyz(mats: np.ndarray) -> np.ndarray:
    return Rotation.from_matrix(mats).as_quat()[..., [3, 0, 1, 2]]


def _solve_by_relations(obj, result, levels, parents, relations, root_head, progress):
    """Local rotations (per bone (F, 4)) and the root's location (F, 3): bones with a constant relation
    in numpy for all frames at once, the rest (blends) by one evaluation per frame and level."""
    col = {b: i for i, b in enumerate(result.bones)}
    want = result.world_rotation                                          # (F, k, 3, 3)
    n = want.shape[0]
    basis_rot = {}
    for b, (anchor, c) in relations.items():                              # B = C^T R_anchor^T R_bone
        parent_t = np.swapaxes(want[:, col[anchor]], -1, -2) if anchor else np.eye(3)
        basis_rot[b] = c[:3, :3].T @ parent_t @ want[:, col[b]]
    root_loc = np.zeros((n, 3))
    root_rigid = relations.get(result.root, ("-", None))[0] is None
    if root_rigid:
        c = relations[result.root][1]
        root_loc = (root_head - c[:3, 3]) @ c[:3, :3]                      # C_R^T (head - C_t)
    quats = {b: _quat_wxyz(r) for b, r in basis_rot.items()}
    # loose bones grouped by how many loose bones they hang below: one evaluation per group and frame
    free = [b for level in levels for b in level if b not in basis_rot]
    if not root_rigid and result.root in basis_rot:                     # rotation rigid, location not
        free = [result.root] + free
    depth = {b: sum(a in free for a in _ancestors(b, parents)) for b in free}
    loose = [[b for b in free if depth[b] == k] for k in range(max(depth.values(), default=-1) + 1)]
    if not loose:
        return quats, root_loc
    for level in loose:
        for b in level:
            quats[b] = np.empty((n, 4))
    layer = bpy.context.view_layer
    for t in range(n):
        for b, r in basis_rot.items():
            pb = obj.pose.bones[b]
            m = Matrix(r[t].tolist()).to_4x4()
            m.translation = root_loc[t].tolist() if b == result.root else pb.location
            pb.matrix_basis = m
        for level in loose:
            layer.update()
            for b in level:
                pb = obj.pose.bones[b]
                m = Matrix(want[t, col[b]].tolist()).to_4x4()
                m.translation = root_head[t].tolist() if b == result.root else pb.head
                pb.matrix = m
                quats[b][t] = tuple(pb.matrix_basis.to_quaternion())
                if b == result.root:
                    root_loc[t] = tuple(pb.location)
        if progress is not None and (t % 25 == 24 or t == n - 1):
            progress((t + 1) / n)
    return quats, root_loc


def _solve_by_evaluation(obj, result, keyed, levels, root_head, progress):
    """Every bone set frame by frame, level by level, with the rig evaluated in between (any rig)."""
    col = {b: i for i, b in enumerate(result.bones)}
    n = result.world_rotation.shape[0]
    quats = {b: np.empty((n, 4)) for b in keyed}
    root_loc = np.empty((n, 3))
    layer = bpy.context.view_layer
    for t in range(n):
        for level in levels:
            for b in level:
                pb = obj.pose.bones[b]
                m = Matrix(result.world_rotation[t, col[b]].tolist()).to_4x4()
                m.translation = root_head[t].tolist() if b == result.root else pb.head
                pb.matrix = m
            layer.update()
        for b in keyed:
            quats[b][t] = tuple(obj.pose.bones[b].matrix_basis.to_quaternion())
        root_loc[t] = tuple(obj.pose.bones[result.root].location)
        if progress is not None and (t % 25 == 24 or t == n - 1):
            progress((t + 1) / n)
    return quats, root_loc


def _disagreement_deg(obj, result, keyed, quats, root_loc, root_head, frames_idx) -> float:
    """Largest angle (degrees) between the evaluated pose and the solve's on ``frames_idx``; a root head
    off by more than 1 % of the longest keyed bone counts as a miss (inf)."""
    col = {b: i for i, b in enumerate(result.bones)}
    layer = bpy.context.view_layer
    worst = 0.0
    size = max(obj.data.bones[b].length for b in keyed)
    for t in frames_idx:
        for b in keyed:
            pb = obj.pose.bones[b]
            m = Matrix(Rotation.from_quat(quats[b][t][[1, 2, 3, 0]]).as_matrix().tolist()).to_4x4()
            m.translation = (root_loc[t].tolist() if b == result.root else pb.location)
            pb.matrix_basis = m
        layer.update()
        for b in keyed:
            got = _mat(obj.pose.bones[b].matrix)[:3, :3]
            chord = np.linalg.norm(got - result.world_rotation[t, col[b]]) / (2 * np.sqrt(2))   # sin(angle / 2)
            worst = max(worst, float(np.degrees(2 * np.arcsin(min(chord, 1.0)))))
        head = np.array(obj.pose.bones[result.root].head)
        if np.linalg.norm(head - root_head[t]) > 0.01 * size:
            return float("inf")
    return worst


def bake_evaluated(obj, result, frames, logical_parents: dict[str, str | None], progress=None) -> dict:
    """Apply ``result`` (solved on the logical rig) to ``obj``, whose controls hang from constraint-driven
    bones; returns the bake summary like :func:`.apply.bake` plus ``evaluated_bones`` (the bones set
    frame by frame) and ``check_deg`` (the largest disagreement on the check frames).  ``progress
    (fraction)`` hears how far it is (it may raise to cancel: nothing is left behind)."""
    switched = {}
    frames = np.asarray(frames, dtype=float)
    saved_pose = {pb.name: pb.matrix_basis.copy() for pb in obj.pose.bones}
    try:
        with baking(obj) as (action, fcurves):
            if any("_fk" in b for b in result.bones):
                for pb in obj.pose.bones:
                    if "IK_FK" in pb.keys():
                        switched[pb.name] = pb["IK_FK"]
                        pb["IK_FK"] = 1.0
                        compat.set_keys(fcurves, f'pose.bones["{pb.name}"]["IK_FK"]', 0, frames[:1], [1.0],
                                        group=pb.name, interpolation='CONSTANT')
            keyed = [b for b in result.bones if b in obj.pose.bones]
            parents = {b: logical_parents.get(b) for b in keyed}
            levels = _levels(keyed, parents)
            root_head = result.heads[:, result.placed.index(result.root)]
            n = len(frames)
            relations = rigid_relations(obj, keyed, parents, result.root)
            quats, root_loc = _solve_by_relations(obj, result, levels, parents, relations, root_head, progress)
            loose = [b for b in keyed if b not in relations]
            check = np.unique(np.linspace(0, n - 1, min(n, 7)).round().astype(int))
            worst = _disagreement_deg(obj, result, keyed, quats, root_loc, root_head, check)
            if worst > CHECK_DEG:                         # a relation that held in the probes did not here
                quats, root_loc = _solve_by_evaluation(obj, result, keyed, levels, root_head, progress)
                loose = list(keyed)
                worst = _disagreement_deg(obj, result, keyed, quats, root_loc, root_head, check)
            for b in keyed:
                key_rotation(obj, fcurves, b, frames, sign_continuous(quats[b]))
            key_location(fcurves, result.root, frames, root_loc)
    except BaseException:
        for name, value in switched.items():
            obj.pose.bones[name]["IK_FK"] = value
        for name, m in saved_pose.items():
            obj.pose.bones[name].matrix_basis = m
        raise
    keys = n * len(keyed)
    return {"action": action, "keys": keys, "keys_before": keys, "error_deg": 0.0, "evaluated": True,
            "evaluated_bones": loose, "check_deg": worst}
