"""core.retarget: bone maps from names and shape, the solve (facing, scale, IK, planted feet), clean curves."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from core.retarget import BoneMapError, RetargetSettings, TargetRig, check_bone_map, guess_bone_map, retarget
from core.retarget.bone_map import words
from core.retarget.curves import euler_continuous, interpolation_error_deg, reduce_keys, reduce_quaternion_keys
from core.retarget.rig import rest_from_head_tail_roll
from core.retarget.solve import two_bone_ik
from core.runs import runs as _runs
from core.skeleton import CLASSES
from core.skeleton import JOINT_INDEX as J
from core.synthetic.motion import load_motion
from core.synthetic.procedural import adult_class_lengths
from core.synthetic.synth import synthesize


def _points(height=1.8, arm_drop_deg=35.0):
    c = dict(zip(CLASSES, adult_class_lengths(height)))
    p = {"hips": np.array([0.0, 0.0, 0.039 * height + c["shank"] + c["thigh"]])}
    p["spine"] = p["hips"] + [0, 0, c["lower_spine"]]
    p["chest"] = p["spine"] + [0, 0, c["upper_spine"]]
    p["neck"] = p["chest"] + [0, 0, c["neck"]]
    p["top"] = p["neck"] + [0, 0, c["head"]]
    a = np.radians(arm_drop_deg)
    for s, sign in (("L", 1.0), ("R", -1.0)):
        p[f"hip{s}"] = p["hips"] + [sign * c["hip"], 0, 0]
        p[f"knee{s}"] = p[f"hip{s}"] + [0, -0.01, -c["thigh"]]
        p[f"ankle{s}"] = p[f"hip{s}"] + [0, 0, -c["thigh"] - c["shank"]]
        p[f"toe{s}"] = p[f"ankle{s}"] + [0, -0.13, -0.06]
        p[f"shoulder{s}"] = p["chest"] + [sign * c["clavicle"], 0, 0]
        d = np.array([sign * np.cos(a), 0, -np.sin(a)])
        p[f"elbow{s}"] = p[f"shoulder{s}"] + d * c["upper_arm"]
        p[f"wrist{s}"] = p[f"elbow{s}"] + d * c["forearm"]
        p[f"finger{s}"] = p[f"wrist{s}"] + d * 0.09
    return p


#: (name pattern, head, tail, parent pattern); {s}/{S}/{side} filled per side.
_UE = [("pelvis", "hips", "spine", None), ("spine_01", "spine", "mid", "pelvis"),
       ("spine_03", "mid", "chest", "spine_01"), ("neck_01", "chest", "neck", "spine_03"),
       ("head", "neck", "top", "neck_01")]
_UE_SIDE = [("thigh_{s}", "hip{S}", "knee{S}", "pelvis"), ("calf_{s}", "knee{S}", "ankle{S}", "thigh_{s}"),
            ("calf_twist_01_{s}", "knee{S}", "ankle{S}", "calf_{s}"),
            ("foot_{s}", "ankle{S}", "toe{S}", "calf_{s}"), ("ball_{s}", "toe{S}", "toe{S}+", "foot_{s}"),
            ("clavicle_{s}", "chest", "shoulder{S}", "spine_03"),
            ("upperarm_{s}", "shoulder{S}", "elbow{S}", "clavicle_{s}"),
            ("lowerarm_{s}", "elbow{S}", "wrist{S}", "upperarm_{s}"),
            ("hand_{s}", "wrist{S}", "finger{S}", "lowerarm_{s}"),
            ("ik_hand_{s}", "finger{S}", "finger{S}+", "hand_{s}")]


def _rig(spec, side_spec, p, *, turn=None):
    """A TargetRig from name patterns; ``turn`` (3x3) rotates the whole rig (another facing or up axis)."""
    pts = dict(p)
    pts["top+"] = p["top"] + [0, 0, 0.05]
    pts["mid"] = 0.5 * (p["spine"] + p["chest"])
    pts["top++"] = p["top"] + [0, 0, 0.08]
    for s in "LR":
        pts[f"toe{s}+"] = p[f"toe{s}"] + [0, -0.05, 0]
        pts[f"finger{s}+"] = p[f"finger{s}"] + [0, 0, -0.03]
    bones = list(spec)
    for s in "LR":
        bones += [tuple(x.format(s=s.lower(), S=s) if x else x for x in b) for b in side_spec]
    names = [b[0] for b in bones]
    turn = np.eye(3) if turn is None else turn
    head = np.array([pts[b[1]] for b in bones]) @ turn.T
    tail = np.array([pts[b[2]] for b in bones]) @ turn.T
    rest = np.array([rest_from_head_tail_roll(h, t, turn @ [0.3, -1.0, 0.2]) for h, t in zip(head, tail)])
    parents = [names.index(b[3]) if b[3] else -1 for b in bones]
    return TargetRig(names, parents, head, tail, rest)


def _mixamo(p, turn=None):
    m = "mixamorig:"
    bones = [(m + "Hips", "hips", "spine", None), (m + "Spine", "spine", "mid", m + "Hips"),
             (m + "Spine2", "mid", "chest", m + "Spine"), (m + "Neck", "chest", "neck", m + "Spine2"),
             (m + "Head", "neck", "top", m + "Neck"), (m + "HeadTop_End", "top", "top+", m + "Head")]
    for s, side in (("L", "Left"), ("R", "Right")):
        x = m + side
        bones += [(x + "UpLeg", f"hip{s}", f"knee{s}", m + "Hips"), (x + "Leg", f"knee{s}", f"ankle{s}", x + "UpLeg"),
                  (x + "Foot", f"ankle{s}", f"toe{s}", x + "Leg"), (x + "ToeBase", f"toe{s}", f"toe{s}+", x + "Foot"),
                  (x + "Shoulder", "chest", f"shoulder{s}", m + "Spine2"),
                  (x + "Arm", f"shoulder{s}", f"elbow{s}", x + "Shoulder"),
                  (x + "ForeArm", f"elbow{s}", f"wrist{s}", x + "Arm"),
                  (x + "Hand", f"wrist{s}", f"finger{s}", x + "ForeArm"),
                  (x + "HandIndex1", f"finger{s}", f"finger{s}+", x + "Hand")]
    return _rig(bones, [], p, turn=turn)


@pytest.fixture(scope="module")
def walk():
    _, truth = synthesize(load_motion("builtin:walk", max_frames=150), kinds=("still",), seed=2)
    w = np.asarray(truth.world_from_cam0)
    return truth.joints_3d @ w[:3, :3].T + w[:3, 3], list(truth.stance), float(truth.fps)


def test_words_split_namespaces_separators_and_camel_case():
    assert words("mixamorig:LeftForeArm") == ["left", "fore", "arm"]
    assert words("upperarm_twist_01_l") == ["upperarm", "twist", "l"]
    assert words("thigh_fk.L") == ["thigh", "fk", "l"]


@pytest.mark.parametrize("make, expected", [
    (lambda p: _mixamo(p), {"hips": "mixamorig:Hips", "chest": "mixamorig:Spine2", "head": "mixamorig:Head",
                            "upper_arm.L": "mixamorig:LeftArm", "shin.R": "mixamorig:RightLeg",
                            "toe.L": "mixamorig:LeftToeBase", "clavicle.R": "mixamorig:RightShoulder"}),
    (lambda p: _rig(_UE, _UE_SIDE, p), {"hips": "pelvis", "chest": "spine_03", "head": "head",
                                         "forearm.L": "lowerarm_l", "shin.L": "calf_l", "toe.R": "ball_r",
                                         "hand.R": "hand_r", "clavicle.L": "clavicle_l"}),
])
def test_bone_maps_are_guessed_from_names_and_chains(make, expected):
    rig = make(_points())
    guessed = guess_bone_map(rig)
    assert {k: guessed[k] for k in expected} == expected
    assert not any("twist" in b or "ik_" in b or "Index" in b for b in guessed.values())
    check_bone_map(rig, guessed)


def test_bad_bone_maps_say_what_is_wrong():
    rig = _mixamo(_points())
    good = guess_bone_map(rig)
    with pytest.raises(BoneMapError, match="thigh.L"):
        check_bone_map(rig, {k: v for k, v in good.items() if k != "thigh.L"})
    with pytest.raises(BoneMapError, match="no bone 'nope'"):
        check_bone_map(rig, {**good, "head": "nope"})
    with pytest.raises(BoneMapError, match="must hang below"):
        check_bone_map(rig, {**good, "forearm.L": "mixamorig:LeftShoulder", "clavicle.L": ""})
    with pytest.raises(BoneMapError, match="two roles"):
        check_bone_map(rig, {**good, "hand.R": "mixamorig:LeftHand"})


def _fk_ends(rig, res, names):
    idx = {n: i for i, n in enumerate(res.placed)}
    return np.stack([res.heads[:, idx[n]] for n in names], axis=1)


@pytest.mark.parametrize("turn", [None, Rotation.from_euler("z", 180, degrees=True).as_matrix(),
                                  Rotation.from_euler("x", -90, degrees=True).as_matrix()],
                         ids=["faces -Y, Z up", "faces +Y", "Y up (raw FBX axes)"])
def test_feet_and_hands_follow_whichever_way_the_rig_faces(walk, turn):
    joints, stance, fps = walk
    rig = _mixamo(_points(), turn)
    res = retarget(rig, guess_bone_map(rig), joints, fps=fps, settings=RetargetSettings(plant_feet=False))
    assert res.end_error.max() < 1e-6                       # every IK goal reached
    feet = _fk_ends(rig, res, ["mixamorig:LeftFoot", "mixamorig:RightFoot"])
    up = (turn if turn is not None else np.eye(3)) @ [0, 0, 1.0]
    left = (turn if turn is not None else np.eye(3)) @ [1.0, 0, 0]
    # the motion keeps its shape: heights above the lowest foot, and the left foot stays on the rig's left
    src_h = joints[:, J["l_ankle"], 2] - joints[:, [J["l_ankle"], J["r_ankle"]], 2].min()
    got_h = feet[:, 0] @ up - (feet @ up).min()
    np.testing.assert_allclose(got_h, res.scale * src_h, atol=0.01)
    # the left foot stays on the body's left, as far from the right foot as the source's (scaled)
    thighs = _fk_ends(rig, res, ["mixamorig:LeftUpLeg", "mixamorig:RightUpLeg"])
    src_side = np.sum((joints[:, J["l_ankle"]] - joints[:, J["r_ankle"]])
                      * (joints[:, J["l_hip"]] - joints[:, J["r_hip"]]), axis=1)
    got_side = np.sum((feet[:, 0] - feet[:, 1]) * (thighs[:, 0] - thighs[:, 1]), axis=1)
    assert np.array_equal(np.sign(src_side), np.sign(got_side))
    np.testing.assert_allclose(np.linalg.norm(feet[:, 0] - feet[:, 1], axis=1),
                               res.scale * np.linalg.norm(joints[:, J["l_ankle"]] - joints[:, J["r_ankle"]], axis=1),
                               atol=1e-6)
    assert abs(left @ (thighs[0, 0] - thighs[0, 1])) > 0     # the rig's own left axis is used


def test_planted_feet_hold_still_and_blend(walk):
    joints, stance, fps = walk
    rig = _mixamo(_points())
    res = retarget(rig, guess_bone_map(rig), joints, fps=fps, stance=stance)
    ends = res.reached[:, :2]
    held = 0
    for side in range(2):
        for a, b in _runs(res.contact[:, side]):
            ground = ends[a:b, side, :2]
            assert np.linalg.norm(ground - ground.mean(axis=0), axis=1).max() < 1e-6
            held += 1
    assert held >= 6
    # the blend is gradual: no frame-to-frame jump of a foot larger than the free motion's largest
    free = retarget(rig, guess_bone_map(rig), joints, fps=fps, settings=RetargetSettings(plant_feet=False))
    step = np.linalg.norm(np.diff(ends, axis=0), axis=-1).max()
    assert step < 1.5 * np.linalg.norm(np.diff(free.reached[:, :2], axis=0), axis=-1).max()


def test_a_stance_the_foot_does_not_keep_is_not_planted(walk):
    """The estimate's stance is believed only where the foot is near the floor and not fast, and a
    contact over which the source ankle wanders is dropped: a wrong stance must not drag the foot."""
    from core.retarget.solve import contact_masks

    joints, stance, fps = walk
    s = RetargetSettings()
    honest = contact_masks(joints, fps, stance, s)
    assert honest.any()
    # the swing foot said to stand: it is up or moving, so it is not planted
    swapped = [{"l": "r", "r": "l"}.get(st, st) for st in stance]
    lied = contact_masks(joints, fps, swapped, s)
    alone = contact_masks(joints, fps, None, s)
    said = np.stack([[st == side for st in swapped] for side in "lr"], axis=1)
    assert (said & ~alone).sum() > 30 and (lied & ~alone).sum() <= 3
    # a foot that slides 30 cm while it is said to stand and is low and slow: dropped
    slid = joints.copy()
    a, b = next((a, b) for a, b in _runs(honest[:, 0]) if b - a >= 6)
    slid[a:b, J["l_ankle"], 0] += np.linspace(0.0, 0.3, b - a)
    assert not contact_masks(slid, fps, stance, RetargetSettings(contact_speed_m_s=10.0))[a:b, 0].any()
    assert contact_masks(slid, fps, stance, RetargetSettings(contact_speed_m_s=10.0, contact_drift_m=1.0))[a:b, 0].all()


def test_rotations_are_continuous_and_smoothing_removes_jitter(walk):
    joints, stance, fps = walk
    rig = _mixamo(_points())
    rng = np.random.default_rng(1)
    noisy = joints + rng.normal(scale=0.01, size=joints.shape)
    rough = retarget(rig, guess_bone_map(rig), noisy, fps=fps)
    smooth = retarget(rig, guess_bone_map(rig), noisy, fps=fps, settings=RetargetSettings(smooth_hz=6.0))
    for res in (rough, smooth):
        dots = np.abs(np.sum(res.rotation[1:] * res.rotation[:-1], axis=-1))
        assert np.sum(res.rotation[1:] * res.rotation[:-1], axis=-1).min() > 0      # sign-continuous
        assert np.degrees(2 * np.arccos(np.clip(dots, -1, 1))).max() < 60               # no flips

    def jitter(res):
        return np.abs(np.diff(res.rotation, n=2, axis=0)).mean()

    assert jitter(smooth) < 0.5 * jitter(rough)


def test_two_bone_ik_reaches_and_bends_toward_the_pole():
    root = np.zeros((3, 3))
    target = np.array([[0.0, 0.0, -0.8], [0.0, 0.3, -0.5], [0.0, 0.0, -2.0]])
    pole = np.tile([0.0, -1.0, 0.0], (3, 1))
    mid, end = two_bone_ik(root, target, 0.5, 0.45, pole)
    np.testing.assert_allclose(end[:2], target[:2], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(mid, axis=1), 0.5, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(end - mid, axis=1), 0.45, atol=1e-9)
    assert mid[0, 1] < 0                                    # toward the pole
    assert np.linalg.norm(end[2]) == pytest.approx(0.95, rel=1e-5)     # out of reach: in line, stretched


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_euler_keys_reproduce_the_rotation_without_jumps(order):
    t = np.linspace(0, 1, 200)
    # the first angle spins twice round (past +-180 degrees), the middle one stays clear of gimbal lock
    seq = np.stack([4 * np.pi * t, 0.8 * np.sin(5 * t), 2.5 * np.cos(3 * t)], axis=1)
    rot = Rotation.from_euler(order.lower(), seq)
    q = rot.as_quat()[:, [3, 0, 1, 2]]
    xyz = euler_continuous(q, order)
    back = Rotation.from_euler(order.lower(), xyz[:, ["xyz".index(a) for a in order.lower()]])
    assert np.degrees((back * rot.inv()).magnitude()).max() < 1e-6
    assert np.abs(np.diff(xyz, axis=0)).max() < np.radians(30)


def test_key_reduction_keeps_the_error_bound():
    t = np.linspace(0, 4, 400)
    v = np.stack([np.sin(t), np.cos(3 * t)], axis=1)
    keep = reduce_keys(v, 0.01)
    interp = np.stack([np.interp(np.arange(400), keep, v[keep, c]) for c in range(2)], axis=1)
    assert np.abs(interp - v).max() <= 0.01 and len(keep) < 100
    q = Rotation.from_rotvec(np.outer(np.sin(t), [0.3, 1.0, 0.2])).as_quat()[:, [3, 0, 1, 2]]
    keep = reduce_quaternion_keys(q, 0.5)
    assert interpolation_error_deg(q, keep) <= 0.5 and len(keep) < 150


@pytest.mark.parametrize("make", [lambda p: _mixamo(p), lambda p: _rig(_UE, _UE_SIDE, p),
                                  lambda p: _mixamo(p, Rotation.from_euler("x", -90, degrees=True).as_matrix()),
                                  lambda p: _rig(_UE, _UE_SIDE, p, turn=np.diag([-1.0, -1.0, 1.0]))],
                         ids=["mixamo", "unreal", "mixamo Y-up", "unreal facing +Y"])
def test_rigs_with_meaningless_names_are_mapped_by_shape(make):
    """Every bone renamed "Bone.NNN": the map comes from the tree's shape and matches the named one."""
    rig = make(_points())
    named = guess_bone_map(rig)
    anonymous = TargetRig([f"Bone.{i:03d}" for i in range(rig.n)], rig.parents, rig.head, rig.tail, rig.rest)
    shaped = guess_bone_map(anonymous)
    expected = {role: f"Bone.{rig.index[bone]:03d}" for role, bone in named.items()}
    helpers = {f"Bone.{i:03d}" for i, n in enumerate(rig.names) if "twist" in n or "ik_" in n}
    assert {r: b for r, b in shaped.items() if r in expected} == expected
    check_bone_map(anonymous, shaped)
    # and the motion it drives is the named map's
    assert not helpers & set(shaped.values())
