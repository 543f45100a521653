"""Bake the retargeted motion onto the target rig: one action of keys, written in bulk.

The action, the keys in each bone's rotation mode and the way back on failure are :mod:`.keys`'s;
if anything fails, the rig gets its previous action back and nothing new is left behind.  Rigs whose
controls hang from constraint-driven bones are baked by evaluation instead (:mod:`.evaluated`).
"""

from __future__ import annotations

import numpy as np

from ...core.retarget import RetargetSettings, retarget
from ...core.retarget.curves import interpolation_error_deg, reduce_quaternion_keys
from . import bone_map_store
from .keys import baking, key_location, key_rotation
from .rig_io import target_rig


def bake(obj, result, frames: np.ndarray, *, max_error_deg: float = 0.0, progress=None) -> dict:
    """Write ``result`` (:class:`core.retarget.RetargetResult`) as keys at scene ``frames`` (F,) on ``obj``.

    ``max_error_deg`` > 0 keeps only the keys needed to stay within that angle (per bone).
    ``progress(fraction)`` hears each bone done (it may raise to cancel: the rig keeps what it had).
    Returns {"action", "keys", "keys_before", "error_deg"}.
    """
    frames = np.asarray(frames, dtype=float)
    with baking(obj) as (action, fcurves):
        keys = before = 0
        worst = 0.0
        for col, name in enumerate(result.bones):
            q = result.rotation[:, col]
            keep = reduce_quaternion_keys(q, max_error_deg) if max_error_deg > 0 else np.arange(len(q))
            if max_error_deg > 0:
                worst = max(worst, interpolation_error_deg(q, keep))
            before += len(q)
            keys += len(keep)
            key_rotation(obj, fcurves, name, frames[keep], q[keep])
            if progress is not None:
                progress((col + 1) / len(result.bones))
        key_location(fcurves, result.root, frames, result.root_location)
    return {"action": action, "keys": keys, "keys_before": before, "error_deg": worst}


def needs_evaluation(obj, rig, bone_map: dict[str, str]) -> bool:
    """True when the direct bake cannot be exact: the mapped bones do not hang from one another as a
    body does, or a bone on the way between them (or one of them) is moved by constraints."""
    from ...core.retarget.bone_map import BoneMapHierarchyError, check_bone_map

    try:
        roles = check_bone_map(rig, bone_map)
    except BoneMapHierarchyError:
        return True
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

    Returns (result, bake summary); the map is then stored with the rig.  The source is taken to the
    armature's own space by the solve (facing, scale, floor); the object's transform then places the
    character in the scene.  Rigs with constraint-driven controls (a generated Rigify rig) are solved
    on their mapped bones alone and baked through the relations the rig's evaluation shows
    (:mod:`.evaluated`).  ``progress(fraction)`` hears how far the bake is.
    """
    from ...core.retarget.bone_map import logical_rig

    rig = target_rig(obj)
    if not needs_evaluation(obj, rig, bone_map):
        result = retarget(rig, bone_map, joints, fps=fps, stance=stance, settings=settings)
        summary = bake(obj, result, frames, max_error_deg=max_error_deg, progress=progress)
    else:
        from .evaluated import bake_evaluated

        body = logical_rig(rig, bone_map)
        result = retarget(body, bone_map, joints, fps=fps, stance=stance, settings=settings)
        parents = {body.names[i]: (body.names[p] if p >= 0 else None) for i, p in enumerate(body.parents)}
        summary = bake_evaluated(obj, result, frames, parents, progress)
        loose = summary["evaluated_bones"]
        result.notes.append("controls hang from constraint-driven bones; " + (
            f"{', '.join(loose)} follow a blend of others and were baked by evaluating the rig frame by frame"
            if loose else "each keeps a fixed relation to the one above it, solved for all frames at once"))
    bone_map_store.store(obj, bone_map)          # the map that drove the rig stays with it
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
