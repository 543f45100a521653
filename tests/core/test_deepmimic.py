"""DeepMimic motion files written as BVH (core.io.deepmimic): the same joints in the world, a skeleton the
BVH mapping reads with its sides right, and one-line errors for files that are not DeepMimic's."""

import json
import subprocess
import sys

import numpy as np
import pytest

from core.errors import InputError
from core.io.bvh import format_bvh, parse_bvh
from core.io.bvh_mapping import canonical_positions
from core.io.deepmimic import motion_to_bvh, read_character
from core.skeleton import JOINT_INDEX

# A small humanoid in DeepMimic's layout: y up, facing +x, its right side at +z.
JOINTS = [
    ("root", "none", -1, (0.0, 0.0, 0.0)),
    ("chest", "spherical", 0, (0.0, 0.24, 0.0)),
    ("neck", "spherical", 1, (0.0, 0.22, 0.0)),
    ("right_hip", "spherical", 0, (0.0, 0.0, 0.09)),
    ("right_knee", "revolute", 3, (0.0, -0.42, 0.0)),
    ("right_ankle", "spherical", 4, (0.0, -0.41, 0.0)),
    ("right_shoulder", "spherical", 1, (-0.02, 0.24, 0.18)),
    ("right_elbow", "revolute", 6, (0.0, -0.27, 0.0)),
    ("right_wrist", "fixed", 7, (0.0, -0.26, 0.0)),
    ("left_hip", "spherical", 0, (0.0, 0.0, -0.09)),
    ("left_knee", "revolute", 9, (0.0, -0.42, 0.0)),
    ("left_ankle", "spherical", 10, (0.0, -0.41, 0.0)),
    ("left_shoulder", "spherical", 1, (-0.02, 0.24, -0.18)),
    ("left_elbow", "revolute", 12, (0.0, -0.27, 0.0)),
    ("left_wrist", "fixed", 13, (0.0, -0.26, 0.0)),
]


def _character(path):
    joints = [{"ID": k, "Name": n, "Type": t, "Parent": p, "AttachX": o[0], "AttachY": o[1], "AttachZ": o[2]}
              for k, (n, t, p, o) in enumerate(JOINTS)]
    path.write_text(json.dumps({"Skeleton": {"Joints": joints}}))
    return str(path)


def _rodrigues(axis_angle):
    theta = np.linalg.norm(axis_angle)
    k = axis_angle / theta
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def _walkish_motion(n=12, seed=0):
    """Frames of a moderate random motion, and each frame's rotations per joint (from axis-angles)."""
    rng = np.random.default_rng(seed)
    rows, rotations = [], []
    for t in range(n):
        row, rots = [1.0 / 30.0, 0.1 * t, 0.9, 0.02 * t], []
        for _, kind, _, _ in JOINTS:
            if kind in ("none", "spherical"):
                aa = rng.normal(0.0, 0.3, 3) + (np.array([0.0, 0.5, 0.0]) if kind == "none" else 0.0)
                theta = np.linalg.norm(aa)
                row += [np.cos(theta / 2), *(np.sin(theta / 2) * aa / theta)]
                rots.append(_rodrigues(aa))
            elif kind == "revolute":
                angle = -abs(rng.normal(0.6, 0.3))           # knees and elbows bend one way
                row.append(angle)
                rots.append(_rodrigues(np.array([0.0, 0.0, angle])))
            else:
                rots.append(np.eye(3))
        rows.append(row)
        rotations.append(rots)
    return np.array(rows), rotations


def _world(frames, rotations):
    """Every joint's place: each joint at its parent's place plus the parent's turn of its offset."""
    out = np.zeros((len(frames), len(JOINTS), 3))
    for t, rots in enumerate(rotations):
        turn = [None] * len(JOINTS)
        for k, (_, _, parent, offset) in enumerate(JOINTS):
            if parent < 0:
                out[t, k], turn[k] = frames[t, 1:4], rots[k]
            else:
                out[t, k] = out[t, parent] + turn[parent] @ np.array(offset)
                turn[k] = turn[parent] @ rots[k]
    return out


@pytest.fixture
def converted(tmp_path):
    frames, rotations = _walkish_motion()
    motion = tmp_path / "walk.txt"
    motion.write_text(json.dumps({"Loop": "none", "Frames": frames.tolist()}))
    bvh = parse_bvh(format_bvh(motion_to_bvh(read_character(_character(tmp_path / "humanoid.txt")), str(motion))))
    return bvh, _world(frames, rotations)


def test_the_bvh_puts_every_joint_where_the_motion_does(converted):
    bvh, world = converted
    assert bvh.fps == pytest.approx(30.0)
    placed = bvh.world_positions() / 100.0                    # written in centimetres
    bvh_names = {"root": "Hips", "chest": "Chest", "neck": "Neck", "right_hip": "RightUpLeg",
                 "right_knee": "RightLeg", "right_ankle": "RightFoot", "right_shoulder": "RightArm",
                 "right_elbow": "RightForeArm", "right_wrist": "RightHand", "left_hip": "LeftUpLeg",
                 "left_knee": "LeftLeg", "left_ankle": "LeftFoot", "left_shoulder": "LeftArm",
                 "left_elbow": "LeftForeArm", "left_wrist": "LeftHand"}
    for k, (name, *_) in enumerate(JOINTS):
        np.testing.assert_allclose(placed[:, bvh.index(bvh_names[name])], world[:, k], atol=1e-6)


def test_the_mapping_reads_its_sides_and_puts_the_thorax_at_the_shoulders(converted):
    bvh, world = converted
    canon = canonical_positions(bvh) / 100.0
    for side, dm in (("l", "left"), ("r", "right")):
        for joint, part in (("hip", "hip"), ("knee", "knee"), ("ankle", "ankle"), ("shoulder", "shoulder"),
                            ("elbow", "elbow"), ("wrist", "wrist")):
            k = next(i for i, j in enumerate(JOINTS) if j[0] == f"{dm}_{part}")
            np.testing.assert_allclose(canon[:, JOINT_INDEX[f"{side}_{joint}"]], world[:, k], atol=1e-6)
    # the thorax is where the arms leave the trunk: midway between the shoulders, not the chest joint below
    mid = (world[:, 6] + world[:, 12]) / 2.0
    np.testing.assert_allclose(canon[:, JOINT_INDEX["thorax"]], mid, atol=1e-6)


def test_files_that_are_not_deepmimic_give_one_line_errors(tmp_path):
    character = _character(tmp_path / "humanoid.txt")
    joints = read_character(character)
    short = tmp_path / "short.txt"
    short.write_text(json.dumps({"Frames": [[1 / 30, 0.0, 0.9, 0.0], [1 / 30, 0.0, 0.9, 0.0]]}))
    with pytest.raises(InputError, match="short.txt: 4 numbers a frame, where the character needs 44"):
        motion_to_bvh(joints, str(short))
    with pytest.raises(InputError, match="not a DeepMimic character file"):
        read_character(str(short))
    cmd = [sys.executable, "-m", "core", "deepmimic-to-bvh", str(tmp_path / "missing.txt"),
           "--character", character, "--out", str(tmp_path / "out")]
    done = subprocess.run(cmd, capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [f"error: {tmp_path / 'missing.txt'}: not a DeepMimic motion file "
                                                "(No such file or directory)"]
