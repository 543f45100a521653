"""Baking onto rigs whose controls hang from constraint-driven mechanism bones (a generated Rigify rig).

There a control's local rotation depends on what the constraints of the bones above it do on that
frame, so it cannot be computed from rest poses alone.  Instead, frame by frame and level by level down
the body (hips, then chest and thighs, ...), each mapped control is given the armature-space matrix the
solve asked for (``pose_bone.matrix``), the rig is evaluated, and the local values Blender derived are
collected; the keys are then written in bulk.  Slower than the direct bake, but exact for any rig.
Rigify's limbs are switched to FK (their ``IK_FK`` property keyed to 1) when FK controls are mapped.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from ...core.retarget.curves import euler_continuous
from .. import compat


def _levels(names: list[str], parents: dict[str, str | None]) -> list[list[str]]:
    depth = {}
    for n in names:
        d, p = 0, parents.get(n)
        while p is not None:
            d += 1
            p = parents.get(p)
        depth[n] = d
    return [[n for n in names if depth[n] == k] for k in range(max(depth.values()) + 1)]


def bake_evaluated(obj, result, frames, logical_parents: dict[str, str | None], action_for, progress=None) -> dict:
    """Apply ``result`` (solved on the logical rig) by evaluating ``obj`` frame by frame; returns the bake
    summary like :func:`.apply.bake`.  ``action_for(obj, created)`` gives the action to write into;
    ``progress(fraction)`` hears how far it is (it may raise to cancel: nothing is left behind)."""
    created: list = []
    anim = obj.animation_data
    old_action = anim.action if anim is not None else None
    switched = {}
    try:
        action, _ = action_for(obj, created)
        fcurves = compat.ensure_fcurves(obj)
        frames = np.asarray(frames, dtype=float)
        if any("_fk" in b for b in result.bones):
            for pb in obj.pose.bones:
                if "IK_FK" in pb.keys():
                    switched[pb.name] = pb["IK_FK"]
                    pb["IK_FK"] = 1.0
                    compat.set_keys(fcurves, f'pose.bones["{pb.name}"]["IK_FK"]', 0, frames[:1], [1.0],
                                    group=pb.name, interpolation='CONSTANT')
        keyed = [b for b in result.bones if b in obj.pose.bones]
        levels = _levels(keyed, {b: logical_parents.get(b) for b in keyed})
        col = {b: i for i, b in enumerate(result.bones)}
        root_head = result.heads[:, result.placed.index(result.root)]
        n = len(frames)
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
            if progress is not None and t % 25 == 24:
                progress((t + 1) / n)
        keys = 0
        for b in keyed:
            q = quats[b]
            flip = np.cumsum(np.concatenate([[0], (np.sum(q[1:] * q[:-1], axis=1) < 0).astype(int)])) % 2 == 1
            q[flip] *= -1
            pb = obj.pose.bones[b]
            path = f'pose.bones["{b}"]'
            if pb.rotation_mode == 'AXIS_ANGLE':
                pb.rotation_mode = 'QUATERNION'
            if pb.rotation_mode == 'QUATERNION':
                for c in range(4):
                    compat.set_keys(fcurves, f"{path}.rotation_quaternion", c, frames, q[:, c], group=b)
            else:
                euler = euler_continuous(q, pb.rotation_mode)
                for c in range(3):
                    compat.set_keys(fcurves, f"{path}.rotation_euler", c, frames, euler[:, c], group=b)
            keys += n
        for c in range(3):
            compat.set_keys(fcurves, f'pose.bones["{result.root}"].location', c, frames, root_loc[:, c],
                            group=result.root)
        return {"action": action, "keys": keys, "keys_before": keys, "error_deg": 0.0, "evaluated": True}
    except BaseException:
        for block in created:
            try:
                bpy.data.actions.remove(block)
            except ReferenceError:
                pass
        if obj.animation_data is not None:
            obj.animation_data.action = old_action
        for name, value in switched.items():
            obj.pose.bones[name]["IK_FK"] = value
        raise
