"""Bake the retargeted motion onto the target rig: one action of keys, written in bulk.

The keys go into an action of their own, ``<rig>|MonoSkel`` (tagged ``monoskel_retarget``); running
again rewrites that action in place instead of adding another.  An action the rig had before is kept
(a fake user, so saving does not drop it) and can be put back from the Action editor.  Bones in
quaternion mode get quaternion keys; bones in an Euler mode get Euler keys without 360-degree jumps;
axis-angle bones are switched to quaternions.  If anything fails, the rig gets its previous action
back and nothing new is left behind.
"""

from __future__ import annotations

import numpy as np

from ...core.retarget import RetargetSettings, retarget
from ...core.retarget.curves import euler_continuous, reduce_quaternion_keys
from .. import compat
from .rig_io import target_rig

TAG = "monoskel_retarget"


def _action_for(obj, created: list):
    """(action, previous action) - the rig's MonoSkel action, emptied, or a new one."""
    import bpy

    anim = obj.animation_data or obj.animation_data_create()
    previous = anim.action
    if previous is not None and previous.get(TAG):
        fcurves = compat.find_fcurves(obj)
        if fcurves is not None:
            for fc in list(fcurves):
                fcurves.remove(fc)
        return previous, None
    if previous is not None:
        previous.use_fake_user = True
        anim.action = None
    action = bpy.data.actions.new(f"{obj.name}|MonoSkel")
    action[TAG] = True
    created.append(action)
    anim.action = action
    return action, previous


def bake(obj, result, frames: np.ndarray, *, max_error_deg: float = 0.0) -> dict:
    """Write ``result`` (:class:`core.retarget.RetargetResult`) as keys at scene ``frames`` (F,) on ``obj``.

    ``max_error_deg`` > 0 keeps only the keys needed to stay within that angle (per bone).
    Returns {"action", "keys", "keys_before", "error_deg"}.
    """
    created: list = []
    anim = obj.animation_data
    old_action = anim.action if anim is not None else None
    old_modes = {pb.name: pb.rotation_mode for pb in obj.pose.bones}
    try:
        action, _ = _action_for(obj, created)
        fcurves = compat.ensure_fcurves(obj)
        frames = np.asarray(frames, dtype=float)
        keys = before = 0
        worst = 0.0
        for col, name in enumerate(result.bones):
            pb = obj.pose.bones[name]
            q = result.rotation[:, col]
            keep = reduce_quaternion_keys(q, max_error_deg) if max_error_deg > 0 else np.arange(len(q))
            if max_error_deg > 0:
                from ...core.retarget.curves import interpolation_error_deg

                worst = max(worst, interpolation_error_deg(q, keep))
            before += len(q)
            keys += len(keep)
            path = f'pose.bones["{name}"]'
            if pb.rotation_mode == 'AXIS_ANGLE':
                pb.rotation_mode = 'QUATERNION'
            if pb.rotation_mode == 'QUATERNION':
                for c in range(4):
                    compat.set_keys(fcurves, f"{path}.rotation_quaternion", c, frames[keep], q[keep, c], group=name)
            else:
                euler = euler_continuous(q, pb.rotation_mode)
                for c in range(3):
                    compat.set_keys(fcurves, f"{path}.rotation_euler", c, frames[keep], euler[keep, c], group=name)
        root = f'pose.bones["{result.root}"].location'
        for c in range(3):
            compat.set_keys(fcurves, root, c, frames, result.root_location[:, c], group=result.root)
        return {"action": action, "keys": keys, "keys_before": before, "error_deg": worst}
    except BaseException:
        for block in created:
            try:
                import bpy

                bpy.data.actions.remove(block)
            except ReferenceError:
                pass
        if obj.animation_data is not None:
            obj.animation_data.action = old_action
        for pb in obj.pose.bones:
            pb.rotation_mode = old_modes[pb.name]
        raise


def needs_evaluation(obj, rig, bone_map: dict[str, str]) -> bool:
    """True when the direct bake cannot be exact: the mapped bones do not hang from one another as a
    body does, or a bone on the way between them (or one of them) is moved by constraints."""
    from ...core.retarget.bone_map import BoneMapError, check_bone_map

    try:
        roles = check_bone_map(rig, bone_map)
    except BoneMapError as exc:
        if "must hang below" in str(exc):
            return True
        raise
    mapped = set(roles.values())
    for i in mapped:
        for j in [i] + rig.ancestors(i):
            if j != i and j in mapped:
                break
            if len(obj.pose.bones[rig.names[j]].constraints):
                return True
    return False


def retarget_onto(obj, joints: np.ndarray, frames: np.ndarray, bone_map: dict[str, str], *, fps: float,
                  stance=None, settings: RetargetSettings | None = None, max_error_deg: float = 0.0,
                  progress=None):
    """Solve and bake: source world joints (F, 17, 3) at scene ``frames`` onto armature ``obj``.

    Returns (result, bake summary).  The source is taken to the armature's own space by the solve
    (facing, scale, floor); the object's transform then places the character in the scene.  Rigs with
    constraint-driven controls (a generated Rigify rig) are solved on their mapped bones alone and baked
    by evaluation (:mod:`.evaluated`), which reports ``progress(fraction)`` as it goes.
    """
    from ...core.retarget.bone_map import logical_rig

    rig = target_rig(obj)
    if not needs_evaluation(obj, rig, bone_map):
        result = retarget(rig, bone_map, joints, fps=fps, stance=stance, settings=settings)
        return result, bake(obj, result, frames, max_error_deg=max_error_deg)
    from .evaluated import bake_evaluated

    body = logical_rig(rig, bone_map)
    result = retarget(body, bone_map, joints, fps=fps, stance=stance, settings=settings)
    parents = {body.names[i]: (body.names[p] if p >= 0 else None) for i, p in enumerate(body.parents)}
    summary = bake_evaluated(obj, result, frames, parents, _action_for, progress)
    result.notes.append("controls hang from constraint-driven bones: baked by evaluating the rig frame by frame")
    return result, summary


def source_motion(scene):
    """(world joints (F, 17, 3), scene frames (F,), stance (F,), fps) of the active take's estimate (the
    scene's estimate when there is no take), at the height it was built for."""
    from ...core.errors import InputError
    from .. import build, scene_data
    from ..review import takes

    settings = scene.monoskel
    take = takes.active_take(settings)
    est = takes.load_take_estimate(take) if take is not None else None
    height = (take.height_m if take is not None and take.height_m > 0 else settings.height_m)
    if est is None:
        est = scene_data.load_estimate(scene)
    if est is None:
        raise InputError("Run Estimate first")
    idx, joints = build.world_joints(est, height)
    if idx.size < 2:
        raise InputError("the estimate has no 3D motion to retarget; run a method that solves it")
    stance = [est.frames[i].stance for i in idx]
    fps = scene.render.fps / scene.render.fps_base
    return joints, idx + settings.tracks_first_frame, stance, float(fps)
