"""Mapping real skeletons onto the canonical 17 joints by chain shape."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import InputError
from core.io.bvh import Bvh, make_bvh, read_bvh
from core.io.bvh_mapping import build_mapping, canonical_positions, map_to_canonical, side_from_name
from core.skeleton import JOINT_INDEX, JOINTS, segment_lengths

# ---------------------------------------------------------------- synthetic skeletons (Y up, facing +Z, left = +X)


def lafan1_tree():
    """LaFAN1 joint names and hierarchy (Ubisoft's layout), offsets in cm, T-pose."""
    t = [("Hips", None, (0, 95, 0))]
    for side, sx in (("Left", 1), ("Right", -1)):
        t += [(f"{side}UpLeg", "Hips", (sx * 9, -5, 0)), (f"{side}Leg", f"{side}UpLeg", (0, -43, 0)),
              (f"{side}Foot", f"{side}Leg", (0, -41, 0)), (f"{side}Toe", f"{side}Foot", (0, -5, 13)),
              (f"{side}Toe_End", f"{side}Toe", (0, 0, 5))]
    t += [("Spine", "Hips", (0, 10, 0)), ("Spine1", "Spine", (0, 12, 0)), ("Spine2", "Spine1", (0, 12, 0)),
          ("Neck", "Spine2", (0, 16, 0)), ("Head", "Neck", (0, 9, 0)), ("Head_End", "Head", (0, 18, 0))]
    for side, sx in (("Left", 1), ("Right", -1)):
        t += [(f"{side}Shoulder", "Spine2", (sx * 4, 12, 0)), (f"{side}Arm", f"{side}Shoulder", (sx * 14, 0, 0)),
              (f"{side}ForeArm", f"{side}Arm", (sx * 28, 0, 0)), (f"{side}Hand", f"{side}ForeArm", (sx * 25, 0, 0)),
              (f"{side}Hand_End", f"{side}Hand", (sx * 9, 0, 0))]
    return t


def mixamo_tree():
    """Mixamo names (``mixamorig:`` prefix), spine first under the hips, fingers on the hands."""
    p = "mixamorig:"
    t = [(f"{p}Hips", None, (0, 100, 0)), (f"{p}Spine", f"{p}Hips", (0, 10, 0)),
         (f"{p}Spine1", f"{p}Spine", (0, 12, 0)), (f"{p}Spine2", f"{p}Spine1", (0, 13, 0)),
         (f"{p}Neck", f"{p}Spine2", (0, 15, 0)), (f"{p}Head", f"{p}Neck", (0, 10, 0)),
         (f"{p}HeadTop_End", f"{p}Head", (0, 19, 0))]
    for side, sx in (("Left", 1), ("Right", -1)):
        t += [(f"{p}{side}Shoulder", f"{p}Spine2", (sx * 6, 11, 0)),
              (f"{p}{side}Arm", f"{p}{side}Shoulder", (sx * 12, 0, 0)),
              (f"{p}{side}ForeArm", f"{p}{side}Arm", (sx * 27, 0, 0)),
              (f"{p}{side}Hand", f"{p}{side}ForeArm", (sx * 26, 0, 0))]
        for finger, dz in (("Thumb", 3), ("Index", 1), ("Middle", 0), ("Pinky", -2)):
            t += [(f"{p}{side}Hand{finger}1", f"{p}{side}Hand", (sx * 3, 0, dz)),
                  (f"{p}{side}Hand{finger}2", f"{p}{side}Hand{finger}1", (sx * 4, 0, 0)),
                  (f"{p}{side}Hand{finger}2_End", f"{p}{side}Hand{finger}2", (sx * 3, 0, 0))]
    for side, sx in (("Left", 1), ("Right", -1)):
        t += [(f"{p}{side}UpLeg", f"{p}Hips", (sx * 9, -7, 0)), (f"{p}{side}Leg", f"{p}{side}UpLeg", (0, -43, 0)),
              (f"{p}{side}Foot", f"{p}{side}Leg", (0, -42, 0)),
              (f"{p}{side}ToeBase", f"{p}{side}Foot", (0, -6, 12)),
              (f"{p}{side}Toe_End", f"{p}{side}ToeBase", (0, 0, 7))]
    return t


def walking_motion(tree, n=12, seed=0):
    """Small smooth motion: root walks forward, limbs swing a little."""
    bvh = make_bvh(tree)
    n_channels = bvh.motion.shape[1]
    rng = np.random.default_rng(seed)
    t = np.arange(n)[:, None] / 30.0
    motion = 8.0 * np.sin(2 * np.pi * rng.uniform(0.5, 1.5, n_channels) * t + rng.uniform(0, 6, n_channels))
    motion[:, :3] = np.asarray(tree[0][2]) + np.array([0, 0, 120.0]) * t
    return make_bvh(tree, motion=motion)


def renamed(bvh: Bvh) -> Bvh:
    """The same skeleton and motion with names that say nothing about sides."""
    names = [f"j{i}" for i in range(bvh.n_joints)]
    return Bvh(bvh.path, names, bvh.parents, bvh.offsets, bvh.is_end_site, bvh.channels, bvh.channel_start,
               bvh.frame_time, bvh.motion)


def expected_from(prefix, names):
    return {k: f"{prefix}{v}" for k, v in names.items()}


LAFAN1_EXPECTED = {"pelvis": "Hips", "spine": "Spine", "thorax": "Spine2", "neck": "Neck", "head": "Head_End",
                   "l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot",
                   "r_hip": "RightUpLeg", "r_knee": "RightLeg", "r_ankle": "RightFoot",
                   "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand",
                   "r_shoulder": "RightArm", "r_elbow": "RightForeArm", "r_wrist": "RightHand"}


def test_lafan1_maps():
    bvh = walking_motion(lafan1_tree())
    assert build_mapping(bvh).names(bvh) == LAFAN1_EXPECTED


def test_mixamo_maps():
    bvh = walking_motion(mixamo_tree())
    expected = expected_from("mixamorig:", LAFAN1_EXPECTED)
    expected["head"] = "mixamorig:HeadTop_End"
    assert build_mapping(bvh).names(bvh) == expected


@pytest.mark.parametrize("tree", [lafan1_tree, mixamo_tree])
def test_left_right_from_geometry_when_names_do_not_tell(tree):
    bvh = walking_motion(tree())
    assert map_to_canonical(renamed(bvh)) == map_to_canonical(bvh)


def test_mirrored_names_are_believed():
    """Names win over geometry: a file whose 'Left' chains are on the +X side maps them to l_*."""
    tree = [(n.replace("Left", "TMP").replace("Right", "Left").replace("TMP", "Right"), p and
             p.replace("Left", "TMP").replace("Right", "Left").replace("TMP", "Right"), o) for n, p, o in lafan1_tree()]
    bvh = walking_motion(tree)
    names = build_mapping(bvh).names(bvh)
    assert names["l_knee"] == "LeftLeg"
    # ... and 'LeftLeg' is now the chain on -X
    assert bvh.offsets[bvh.index("LeftUpLeg")][0] < 0


def test_canonical_positions_follow_the_motion():
    bvh = walking_motion(lafan1_tree(), n=5)
    points = canonical_positions(bvh)
    world = bvh.world_positions()
    for name, bvh_name in LAFAN1_EXPECTED.items():
        np.testing.assert_allclose(points[:, JOINT_INDEX[name]], world[:, bvh.index(bvh_name)], atol=1e-12)


# ---------------------------------------------------------------- shared real clips


@pytest.fixture(scope="module")
def shared_clips(shared_bvh_dir):
    return {p.name: read_bvh(p) for p in sorted(shared_bvh_dir.glob("*.bvh"))}


def test_every_shared_clip_maps_plausibly(shared_clips):
    assert len(shared_clips) >= 10
    for name, bvh in shared_clips.items():
        mapping = build_mapping(bvh)
        assert set(mapping.indices) == set(JOINTS), name
        frames = np.linspace(0, bvh.n_frames - 1, 20).round().astype(int)
        p = canonical_positions(bvh, mapping, frames)
        y = np.median(p[..., 1], axis=0)                       # Y is up in all shared clips
        J = JOINT_INDEX
        for side in "lr":
            assert y[J[f"{side}_ankle"]] < y[J[f"{side}_knee"]] < y[J[f"{side}_hip"]], name
        assert y[J["pelvis"]] < y[J["thorax"]] < y[J["neck"]] < y[J["head"]], name
        # every mapped point is distinct from its parent (no zero-length segment)
        assert segment_lengths(p).min() > 0, name
        # named sides agree with the mapped sides
        for side, word in (("l", "l"), ("r", "r")):
            for joint in ("knee", "elbow"):
                bvh_name = bvh.names[mapping.indices[f"{side}_{joint}"]]
                assert side_from_name(bvh_name) == (1 if word == "l" else -1), (name, bvh_name)


def test_shared_clips_sides_from_geometry_match_names(shared_clips):
    for name, bvh in shared_clips.items():
        assert map_to_canonical(renamed(bvh)) == map_to_canonical(bvh), name


@pytest.mark.parametrize("clip, joints", [
    ("01_01.bvh", {"l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot", "l_shoulder": "LeftArm",
                   "l_wrist": "LeftHand", "neck": "Neck1", "head": "Head_End", "thorax": "Spine1"}),
    ("131_01.bvh", {"l_hip": "LeftHip", "l_knee": "LeftKnee", "l_ankle": "LeftAnkle", "l_shoulder": "LeftShoulder",
                    "l_elbow": "LeftElbow", "l_wrist": "LeftWrist", "thorax": "Chest2"}),
    ("bandai_dataset-1_walk_normal_001.bvh", {"pelvis": "Hips", "l_hip": "UpperLeg_L", "r_ankle": "Foot_R",
                                              "l_shoulder": "UpperArm_L", "r_wrist": "Hand_R", "thorax": "Chest"}),
    ("acrnn_martial_04.bvh", {"pelvis": "hip", "l_hip": "lThigh", "l_knee": "lShin", "l_ankle": "lFoot",
                              "r_shoulder": "rShldr", "r_elbow": "rForeArm", "r_wrist": "rHand", "spine": "abdomen"}),
    ("milad_bvh-matlab.bvh", {"l_wrist": "LeftHand", "r_elbow": "RightForeArm", "head": "Head_End"}),
    ("0005_Jogging001.bvh", {"l_shoulder": "LeftArm", "l_hip": "LeftUpLeg", "neck": "Neck"}),
])
def test_known_joint_choices(clip, joints, shared_bvh_dir):
    bvh = read_bvh(shared_bvh_dir / clip)
    names = build_mapping(bvh).names(bvh)
    for canonical, bvh_name in joints.items():
        assert names[canonical] == bvh_name, (clip, canonical)


def test_bandai_head_top_is_synthesised_above_the_head(shared_bvh_dir):
    bvh = read_bvh(shared_bvh_dir / "bandai_dataset-1_walk_normal_001.bvh")
    mapping = build_mapping(bvh)
    assert any(mapping.points["head"].offset)
    p = canonical_positions(bvh, mapping, slice(0, 10))
    head_joint = bvh.world_positions(slice(0, 10))[:, bvh.index("Head")]
    assert np.all(p[:, JOINT_INDEX["head"], 1] > head_joint[:, 1])


# ---------------------------------------------------------------- unmappable skeletons


def _without(tree, prefix):
    return [t for t in tree if not t[0].startswith(prefix)]


@pytest.mark.parametrize("tree, words", [
    ([("Root", None, (0, 0, 0)), ("A", "Root", (0, 1, 0)), ("A_End", "A", (0, 1, 0))], "single chain"),
    (_without(lafan1_tree(), "Right") + [(n, p, o) for n, p, o in lafan1_tree() if n.startswith("RightShoulder")
                                         or n.startswith("RightArm") or n.startswith("RightForeArm")
                                         or n.startswith("RightHand")], "no second leg chain found"),
    ([t for t in lafan1_tree() if "Shoulder" not in t[0] and "Arm" not in t[0] and "Hand" not in t[0]],
     "no upper body"),
])
def test_unmappable_skeletons_say_what_is_missing(tree, words):
    with pytest.raises(InputError, match=words):
        build_mapping(make_bvh(tree, path="odd.bvh"))


def test_three_legs_are_rejected():
    tree = lafan1_tree() + [("TailUp", "Hips", (0, -5, -9)), ("TailLeg", "TailUp", (0, -43, 0)),
                            ("TailFoot", "TailLeg", (0, -41, 0)), ("TailFoot_End", "TailFoot", (0, 0, 10))]
    with pytest.raises(InputError, match="more than two leg chains"):
        build_mapping(make_bvh(tree, path="odd.bvh"))


@pytest.mark.parametrize("name, side", [
    ("LeftUpLeg", 1), ("RightHand", -1), ("mixamorig:LeftArm", 1), ("lThigh", 1), ("rShin", -1),
    ("LHipJoint", 1), ("RThumb", -1), ("UpperLeg_L", 1), ("Hand_R", -1), ("hand.l", 1), ("ShoulderR", -1),
    ("lowerback", 0), ("Hips", 0), ("Head", 0), ("Spine1", 0), ("rightEye", -1), ("L_Wrist_End", 1),
    ("Neck", 0), ("LowerLeg", 0), ("Chest2", 0), ("CC_Base_L_Thigh", 1), ("CC_Base_R_Upperarm", -1),
    ("CC_Base_L_ThighTwist01", 1), ("CC_Base_Hip", 0),
])
def test_side_from_name(name, side):
    assert side_from_name(name) == side


def test_legs_hanging_from_a_shared_pelvis_node():
    tree = []
    for name, parent, offset in lafan1_tree():
        tree.append((name, "Pelvis" if parent == "Hips" and "UpLeg" in name else parent, offset))
    tree.insert(1, ("Pelvis", "Hips", (0, -3, 0)))
    bvh = walking_motion(tree)
    assert build_mapping(bvh).names(bvh) == LAFAN1_EXPECTED


def test_feet_with_toe_and_heel_branches():
    tree = lafan1_tree()
    for side in ("Left", "Right"):
        tree += [(f"{side}Heel", f"{side}Foot", (0, -5, -4)), (f"{side}Heel_End", f"{side}Heel", (0, 0, -2))]
    bvh = walking_motion(tree)
    assert build_mapping(bvh).names(bvh) == LAFAN1_EXPECTED


def character_creator_tree():
    """Character Creator's layout: ``CC_Base_`` names, twist bones along the limbs, and a long hand (three
    finger joints) whose length from the wrist is more than 0.7 of the forearm."""
    b = "CC_Base_"
    t = [(f"{b}Hip", None, (0, 100, 0)), (f"{b}Waist", f"{b}Hip", (0, 8, 0)), (f"{b}Spine01", f"{b}Waist", (0, 10, 0)),
         (f"{b}Spine02", f"{b}Spine01", (0, 16, 0)), (f"{b}NeckTwist01", f"{b}Spine02", (0, 16, 0)),
         (f"{b}Head", f"{b}NeckTwist01", (0, 9, 0)), (f"{b}Head_End", f"{b}Head", (0, 19, 0))]
    for side, sx in (("L", 1), ("R", -1)):
        s = f"{b}{side}_"
        t += [(f"{s}Clavicle", f"{b}Spine02", (sx * 3, 12, 0)), (f"{s}Upperarm", f"{s}Clavicle", (sx * 15, 0, 0)),
              (f"{s}UpperarmTwist01", f"{s}Upperarm", (sx * 9, 0, 0)),
              (f"{s}UpperarmTwist01_End", f"{s}UpperarmTwist01", (sx * 4, 0, 0)),
              (f"{s}Forearm", f"{s}Upperarm", (sx * 27, 0, 0)),
              (f"{s}ForearmTwist01", f"{s}Forearm", (sx * 12, 0, 0)),
              (f"{s}ForearmTwist01_End", f"{s}ForearmTwist01", (sx * 4, 0, 0)),
              (f"{s}Hand", f"{s}Forearm", (sx * 24, 0, 0)), (f"{s}Mid1", f"{s}Hand", (sx * 9, 0, 0)),
              (f"{s}Mid2", f"{s}Mid1", (sx * 4, 0, 0)), (f"{s}Mid3", f"{s}Mid2", (sx * 3, 0, 0)),
              (f"{s}Mid3_End", f"{s}Mid3", (sx * 2.5, 0, 0))]
    for side, sx in (("L", 1), ("R", -1)):
        s = f"{b}{side}_"
        t += [(f"{s}Thigh", f"{b}Hip", (sx * 9, -6, 0)), (f"{s}Calf", f"{s}Thigh", (0, -43, 0)),
              (f"{s}Foot", f"{s}Calf", (0, -41, 0)), (f"{s}ToeBase", f"{s}Foot", (0, -5, 13)),
              (f"{s}ToeBase_End", f"{s}ToeBase", (0, 0, 5))]
    return t


def test_a_long_hand_is_found_by_its_name():
    """By shape alone the hand's 18.5 cm beyond the wrist (more than 0.7 of the 24 cm forearm) would make a
    finger joint the wrist, the hand the elbow and the forearm the shoulder."""
    bvh = walking_motion(character_creator_tree())
    names = build_mapping(bvh).names(bvh)
    for side in ("L", "R"):
        s = side.lower()
        assert (names[f"{s}_shoulder"], names[f"{s}_elbow"], names[f"{s}_wrist"]) == (
            f"CC_Base_{side}_Upperarm", f"CC_Base_{side}_Forearm", f"CC_Base_{side}_Hand")
        assert (names[f"{s}_hip"], names[f"{s}_knee"], names[f"{s}_ankle"]) == (
            f"CC_Base_{side}_Thigh", f"CC_Base_{side}_Calf", f"CC_Base_{side}_Foot")


def test_anonymous_figure_facing_minus_z():
    """Turned by 180 degrees about Y and without telling names: sides still follow the toes."""
    tree = [(name, parent, (-o[0], o[1], -o[2])) for name, parent, o in lafan1_tree()]
    bvh = walking_motion(tree)
    anonymous = renamed(bvh)
    names = {k: bvh.names[v] for k, v in map_to_canonical(anonymous).items()}
    assert names == LAFAN1_EXPECTED


def test_head_without_end_site_gets_a_synthesised_top():
    tree = [t for t in lafan1_tree() if t[0] != "Head_End"]
    bvh = walking_motion(tree, n=4)
    mapping = build_mapping(bvh)
    assert mapping.names(bvh)["head"] == "Head" and any(mapping.points["head"].offset)
    p = canonical_positions(bvh, mapping)
    head_joint = bvh.world_positions()[:, bvh.index("Head")]
    top = p[:, JOINT_INDEX["head"]]
    legs = np.linalg.norm(p[:, JOINT_INDEX["l_knee"]] - p[:, JOINT_INDEX["l_hip"]], axis=-1) + np.linalg.norm(
        p[:, JOINT_INDEX["l_ankle"]] - p[:, JOINT_INDEX["l_knee"]], axis=-1)
    np.testing.assert_allclose(np.linalg.norm(top - head_joint, axis=-1), 0.2 * legs, rtol=0.05)
    assert np.all(top[:, 1] > head_joint[:, 1])
