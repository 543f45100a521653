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

from ...core.retarget.curves import sign_continuous
from .. import compat
from .keys import baking, key_location, key_rotation


def _levels(names: list[str], parents: dict[str, str | None]) -> list[list[str]]:
    depth = {}
    for n in names:
        d, p = 0, parents.get(n)
        while p is not None:
            d += 1
            p = parents.get(p)
        depth[n] = d
    return [[n for n in names if depth[n] == k] for k in range(max(depth.values()) + 1)]


def bake_evaluated(obj, result, frames, logical_parents: dict[str, str | None], progress=None) -> dict:
    """Apply ``result`` (solved on the logical rig) by evaluating ``obj`` frame by frame; returns the bake
    summary like :func:`.apply.bake`.  ``progress(fraction)`` hears how far it is (it may raise to
    cancel: nothing is left behind)."""
    switched = {}
    frames = np.asarray(frames, dtype=float)
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
            for b in keyed:
                key_rotation(obj, fcurves, b, frames, sign_continuous(quats[b]))
            key_location(fcurves, result.root, frames, root_loc)
    except BaseException:
        for name, value in switched.items():
            obj.pose.bones[name]["IK_FK"] = value
        raise
    keys = n * len(keyed)
    return {"action": action, "keys": keys, "keys_before": keys, "error_deg": 0.0, "evaluated": True}
