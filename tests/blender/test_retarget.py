"""Retargeting onto the animator's rig on real bpy: a Mixamo-style armature built here (A-pose,
other rolls, 0.01 scale, Euler legs) and a Rigify metarig made by Rigify's own operator.  Feet and hands
follow the scaled source, planted feet hold, no bone flips, save and reload keep the motion, undo and
failures leave the rig as it was."""

from __future__ import annotations

import numpy as np
import pytest

from tests.blender.rigs import mixamo_rig as _mixamo_rig
from tests.blender.rigs import walk_take as _walk_take


def _world_heads(scene, obj, names, frames):
    out = np.empty((len(frames), len(names), 3))
    for k, f in enumerate(frames):
        scene.frame_set(int(f))
        for j, name in enumerate(names):
            out[k, j] = np.array(obj.matrix_world @ obj.pose.bones[name].head)
    return out


def _source(scene):
    from monoskel.blender.retarget.apply import source_motion

    return source_motion(scene)


def _length(bones, *names):
    return sum((bones[a].head_local - bones[b].head_local).length for a, b in zip(names, names[1:]))


def _check_follows(scene, obj, limbs, *, tol_m=0.02, turn=None):
    """Feet follow the source's feet (scaled by the ratio of leg lengths) and hands the source's hands
    from the shoulders (scaled by the ratio of arm lengths), within ``tol_m`` in every frame.

    ``limbs``: per side (thigh, shin, foot, upper arm, forearm, hand) bone names.  Scales are measured
    here, on the rig's rest and the source joints; ``turn`` (3x3) turns the source's motion the way the
    rig faces relative to the source (None: the same way, -Y).
    """
    from monoskel.core.skeleton import JOINT_INDEX as J

    joints, frames, _, _ = _source(scene)
    if turn is not None:
        joints = joints @ np.asarray(turn).T
    bones = obj.data.bones
    unit = obj.matrix_world.to_scale()[0]

    def src_len(*names):
        return np.median(sum(np.linalg.norm(joints[:, J[b]] - joints[:, J[a]], axis=-1)
                             for a, b in zip(names, names[1:])))

    for (thigh, shin, foot, upper, fore, hand), side in zip(limbs, "lr"):
        got = _world_heads(scene, obj, [foot, upper, hand], frames)
        leg = unit * _length(bones, thigh, shin, foot) / src_len(f"{side}_hip", f"{side}_knee", f"{side}_ankle")
        ankle = joints[:, J[f"{side}_ankle"]]
        feet = np.linalg.norm((got[:, 0] - got[0, 0]) - leg * (ankle - ankle[0]), axis=-1)
        arm = unit * _length(bones, upper, fore, hand) / src_len(f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist")
        reach = joints[:, J[f"{side}_wrist"]] - joints[:, J[f"{side}_shoulder"]]
        hands = np.linalg.norm((got[:, 2] - got[:, 1]) - arm * reach, axis=-1)
        assert feet.max() < tol_m and hands.max() < tol_m, (side, feet.max(), hands.max())


def test_mixamo_feet_and_hands_follow_and_planted_feet_hold(empty_scene):
    import bpy

    from monoskel.blender import compat
    from monoskel.core.retarget.curves import quaternion_angle_deg
    from monoskel.core.runs import runs as _runs

    scene = _walk_take()
    obj = _mixamo_rig(scene)
    s = scene.monoskel
    s.retarget_target = obj
    assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
    shown = {item.role: item.bone for item in s.retarget_map if item.bone}
    assert shown["hips"] == "mixamorig:Hips" and shown["chest"] == "mixamorig:Spine2"
    assert shown["forearm.L"] == "mixamorig:LeftForeArm" and shown["shin.R"] == "mixamorig:RightLeg"
    assert "mixamorig:LeftHandIndex1" not in shown.values()            # fingers are left alone
    s.retarget_plant_feet = False
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    ends = ["mixamorig:LeftFoot", "mixamorig:RightFoot", "mixamorig:LeftHand", "mixamorig:RightHand"]
    _check_follows(scene, obj, [tuple(f"mixamorig:{x}{b}" for b in ("UpLeg", "Leg", "Foot", "Arm", "ForeArm", "Hand"))
                                for x in ("Left", "Right")])
    paths = compat.fcurve_paths(obj)
    assert ('pose.bones["mixamorig:LeftUpLeg"].rotation_euler', 0) in paths          # Euler bones stay Euler
    assert ('pose.bones["mixamorig:LeftForeArm"].rotation_quaternion', 0) in paths
    assert not any("HandIndex1" in p for p, _ in paths) and not any("LeftHand\"" in p for p, _ in paths)
    # no flips: consecutive keys of every quaternion bone turn by far less than 90 degrees
    for path, index in paths:
        if path.endswith("rotation_quaternion") and index == 0:
            q = np.stack([compat.get_keys(obj, path, c)[1] for c in range(4)], axis=1)
            assert quaternion_angle_deg(q[1:], q[:-1]).max() < 45.0, path
        if path.endswith("rotation_euler"):
            v = compat.get_keys(obj, path, index)[1]
            assert np.abs(np.diff(v)).max() < np.radians(45.0), path
    # planted: every contact run of the held feet moves less than 5 mm on the ground
    s.retarget_plant_feet = True
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    assert len([a for a in bpy.data.actions if a.get("monoskel_retarget")]) == 1      # rewritten in place
    from monoskel.blender.retarget.rig_io import target_rig
    from monoskel.core.retarget import retarget
    from monoskel.core.retarget.solve import RetargetSettings

    joints, frames, stance, fps = _source(scene)
    result = retarget(target_rig(obj), {i.role: i.bone for i in s.retarget_map if i.bone}, joints, fps=fps,
                      stance=stance, settings=RetargetSettings())
    feet = _world_heads(scene, obj, ends[:2], frames)
    runs = 0
    for side in range(2):
        for a, b in _runs(result.contact[:, side]):
            a, b = a + 4, b - 4            # the hold is full inside the blend
            if b - a < 3:
                continue
            ground = feet[a:b, side, :2]
            assert np.linalg.norm(ground - ground.mean(axis=0), axis=1).max() <= 0.005
            runs += 1
    assert runs >= 4


def test_unreal_mannequin_names_facing_plus_y(empty_scene):
    import bpy

    from tests.blender.rigs import unreal_name

    scene = _walk_take()
    obj = _mixamo_rig(scene, unreal=True)
    s = scene.monoskel
    s.retarget_target = obj
    s.retarget_plant_feet = False
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    shown = {item.role: item.bone for item in s.retarget_map if item.bone}
    assert (shown["hips"], shown["chest"], shown["thigh.L"], shown["forearm.R"]) == (
        "pelvis", "spine_03", "thigh_l", "lowerarm_r")
    names = [tuple(unreal_name(f"mixamorig:{x}{b}") for b in ("UpLeg", "Leg", "Foot", "Arm", "ForeArm", "Hand"))
             for x in ("Left", "Right")]
    _check_follows(scene, obj, names, turn=np.diag([-1.0, -1.0, 1.0]))
    # facing +Y: the character walks the source's way turned half round, so its first step goes the
    # other way along Y than the source's
    joints, frames, _, _ = _source(scene)
    feet = _world_heads(scene, obj, ["pelvis"], [frames[0], frames[-1]])[:, 0]
    src = joints[[0, -1], 0]
    assert np.sign(feet[1, 1] - feet[0, 1]) == -np.sign(src[1, 1] - src[0, 1])


def test_rigify_metarig_from_rigifys_own_operator(empty_scene):
    import addon_utils
    import bpy

    addon_utils.enable("rigify", default_set=True)
    try:
        scene = _walk_take()
        bpy.ops.object.armature_human_metarig_add()
        obj = bpy.context.object
        s = scene.monoskel
        s.retarget_target = obj
        assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
        shown = {item.role: item.bone for item in s.retarget_map if item.bone}
        assert (shown["hips"], shown["chest"], shown["head"]) == ("spine", "spine.003", "spine.006")
        assert shown["clavicle.L"] == "shoulder.L" and shown["toe.R"] == "toe.R"
        s.retarget_plant_feet = False
        assert bpy.ops.monoskel.retarget() == {"FINISHED"}
        _check_follows(scene, obj, [tuple(f"{b}.{x}" for b in ("thigh", "shin", "foot", "upper_arm", "forearm", "hand"))
                                    for x in "LR"])
    finally:
        addon_utils.disable("rigify", default_set=True)


def test_generated_rigify_rig_through_its_fk_controls(empty_scene):
    """The generated rig's controls hang from constraint-driven mechanism bones: the map picks the FK
    controls, the limbs are switched to FK, and the deforming (ORG) bones follow the source."""
    import addon_utils
    import bpy

    from monoskel.blender import compat

    addon_utils.enable("rigify", default_set=True)
    try:
        scene = _walk_take()
        bpy.ops.object.armature_human_metarig_add()
        bpy.ops.pose.rigify_generate()
        obj = bpy.data.objects["rig"]
        s = scene.monoskel
        s.retarget_target = obj
        assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
        shown = {item.role: item.bone for item in s.retarget_map if item.bone}
        assert (shown["hips"], shown["chest"], shown["head"]) == ("torso", "chest", "head")
        assert shown["thigh.L"] == "thigh_fk.L" and shown["forearm.R"] == "forearm_fk.R"
        assert shown["clavicle.L"] == "shoulder.L"
        s.retarget_plant_feet = False
        assert bpy.ops.monoskel.retarget() == {"FINISHED"}
        assert compat.get_keys(obj, 'pose.bones["thigh_parent.L"]["IK_FK"]')[1][0] == 1.0      # FK on
        _check_follows(scene, obj, [tuple(f"ORG-{b}.{x}" for b in ("thigh", "shin", "foot", "upper_arm", "forearm",
                                                                   "hand")) for x in "LR"])
    finally:
        addon_utils.disable("rigify", default_set=True)


def test_generated_rigify_controls_that_blend_are_baked_by_evaluation(empty_scene):
    """With Rigify's defaults every mapped control keeps a fixed relation to one above it (solved for
    all frames at once); a head that follows the torso half-way and a thigh that follows the root 30 %
    do not, and are set frame by frame: both ways land on the solve's rotations and the ORG bones
    follow the source."""
    import addon_utils
    import bpy

    from monoskel.blender.retarget.apply import retarget_onto
    from monoskel.blender.retarget.rig_io import target_rig
    from monoskel.core.retarget import RetargetSettings, guess_bone_map

    addon_utils.enable("rigify", default_set=True)
    try:
        scene = _walk_take()
        bpy.ops.object.armature_human_metarig_add()
        bpy.ops.pose.rigify_generate()
        obj = bpy.data.objects["rig"]
        joints, frames, stance, fps = _source(scene)
        bone_map = guess_bone_map(target_rig(obj))
        opts = RetargetSettings(plant_feet=False)
        _, fixed = retarget_onto(obj, joints, frames, bone_map, fps=fps, stance=stance, settings=opts)
        assert fixed["evaluated_bones"] == [] and fixed["check_deg"] < 0.01
        obj.pose.bones["torso"]["head_follow"] = 0.5
        obj.pose.bones["thigh_parent.L"]["FK_limb_follow"] = 0.3
        seen = []
        result, blended = retarget_onto(obj, joints, frames, bone_map, fps=fps, stance=stance, settings=opts,
                                        progress=seen.append)
        assert sorted(blended["evaluated_bones"]) == ["head", "thigh_fk.L"] and blended["check_deg"] < 0.01
        assert seen and seen[-1] > 0.9
        col = result.bones.index("head")
        for k in (0, len(frames) // 2, len(frames) - 1):
            scene.frame_set(int(frames[k]))
            got = np.array(obj.pose.bones["head"].matrix.to_3x3())
            assert np.linalg.norm(got - result.world_rotation[k, col]) < 1e-3
        _check_follows(scene, obj, [tuple(f"ORG-{b}.{x}" for b in ("thigh", "shin", "foot", "upper_arm", "forearm",
                                                                   "hand")) for x in "LR"])
    finally:
        addon_utils.disable("rigify", default_set=True)


def test_the_rig_still_plays_after_save_and_reload(empty_scene, tmp_path):
    import bpy

    scene = _walk_take()
    obj = _mixamo_rig(scene)
    scene.monoskel.retarget_target = obj
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    names = ["mixamorig:LeftFoot", "mixamorig:RightHand", "mixamorig:Head"]
    frames = [1, 20, 45, 90]
    before = _world_heads(scene, obj, names, frames)
    path = tmp_path / "rig.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path))
    scene = bpy.context.scene
    obj = bpy.data.objects["Character"]
    np.testing.assert_allclose(_world_heads(scene, obj, names, frames), before, atol=1e-5)
    assert obj.get("monoskel_bone_map")                       # the bone map was saved with the rig
    assert scene.monoskel.retarget_target == obj


def test_undo_and_failures_leave_the_rig_as_it_was(empty_scene):
    import bpy

    scene = _walk_take()
    obj = _mixamo_rig(scene)
    mine = bpy.data.actions.new("animator's action")
    obj.animation_data_create().action = mine
    s = scene.monoskel
    s.retarget_target = obj
    bpy.ops.ed.undo_push(message="before retarget")
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    obj = bpy.data.objects["Character"]
    assert obj.animation_data.action.name == "Character|MonoSkel" and mine.use_fake_user
    bpy.ops.ed.undo_push(message="retargeted")
    bpy.ops.ed.undo()
    obj = bpy.data.objects["Character"]
    assert obj.animation_data.action.name == "animator's action"
    assert "Character|MonoSkel" not in bpy.data.actions
    # a map without the thighs cannot drive the rig: one line, the rig keeps its action, nothing is added
    s = bpy.context.scene.monoskel
    assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
    next(i for i in s.retarget_map if i.role == "thigh.L").bone = ""
    actions = len(bpy.data.actions)
    with pytest.raises(RuntimeError, match="thigh.L"):
        bpy.ops.monoskel.retarget()
    assert obj.animation_data.action.name == "animator's action" and len(bpy.data.actions) == actions
    # a second bake that fails half-way (here: cancelled from its progress report) leaves the first
    # retarget's keys whole, and a second one that succeeds replaces them under the same name
    from monoskel.blender import compat
    from monoskel.blender.retarget.apply import retarget_onto

    assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    first = obj.animation_data.action
    path = 'pose.bones["mixamorig:LeftUpLeg"].rotation_euler'
    keys_before = compat.get_keys(obj, path, 0)
    joints, frames, stance, fps = _source(bpy.context.scene)
    bone_map = {i.role: i.bone for i in s.retarget_map if i.bone}

    def cancel(fraction):
        if fraction > 0.5:
            raise KeyboardInterrupt("cancelled")

    with pytest.raises(KeyboardInterrupt):
        retarget_onto(obj, joints[::-1].copy(), frames, bone_map, fps=fps, stance=stance, progress=cancel)
    assert obj.animation_data.action == first and first.name == "Character|MonoSkel"
    np.testing.assert_array_equal(compat.get_keys(obj, path, 0)[1], keys_before[1])
    assert bpy.ops.monoskel.retarget() == {"FINISHED"}
    assert obj.animation_data.action.name == "Character|MonoSkel"
    assert sum(a.get("monoskel_retarget", False) for a in bpy.data.actions) == 1
    # MonoSkel's own armature is not a target
    s.retarget_target = s.armature
    with pytest.raises(RuntimeError, match="character's armature"):
        bpy.ops.monoskel.retarget()


def test_presets_carry_a_map_to_another_rig(empty_scene, tmp_path):
    import bpy

    scene = _walk_take()
    obj = _mixamo_rig(scene)
    s = scene.monoskel
    s.retarget_target = obj
    assert bpy.ops.monoskel.retarget_guess_map() == {"FINISHED"}
    next(i for i in s.retarget_map if i.role == "hand.L").bone = ""          # an edit the preset keeps
    path = tmp_path / "mixamo.json"
    assert bpy.ops.monoskel.retarget_save_preset(filepath=str(path)) == {"FINISHED"}
    other = _mixamo_rig(scene)
    s.retarget_target = other
    assert bpy.ops.monoskel.retarget_load_preset(filepath=str(path)) == {"FINISHED"}
    loaded = {i.role: i.bone for i in s.retarget_map if i.bone}
    assert s.retarget_map_rig == other.name and "hand.L" not in loaded and loaded["hand.R"] == "mixamorig:RightHand"
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(RuntimeError, match="not a MonoSkel bone-map preset"):
        bpy.ops.monoskel.retarget_load_preset(filepath=str(tmp_path / "bad.json"))
