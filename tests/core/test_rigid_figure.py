"""Rigid symmetric figures from BVH clips, and foot contacts."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import InputError
from core.io.bvh import format_bvh, make_bvh, read_bvh
from core.io.bvh_mapping import canonical_positions
from core.skeleton import (
    ANKLE_HEIGHT_FRACTION,
    FEET,
    JOINT_INDEX,
    SEGMENT_CLASS,
    SEGMENTS,
    segment_lengths,
    standing_height,
)
from core.synthetic.motion import load_motion
from core.synthetic.rigid_figure import foot_contacts, motion_from_bvh_file, resample


def assert_rigid(motion, atol=1e-9):
    lengths = segment_lengths(motion.joints)
    expected = motion.class_lengths[list(SEGMENT_CLASS)]
    np.testing.assert_allclose(lengths, np.broadcast_to(expected, lengths.shape), rtol=0, atol=atol)


@pytest.fixture(scope="module")
def shared_motions(shared_bvh_dir):
    return {p.name: motion_from_bvh_file(p) for p in sorted(shared_bvh_dir.glob("*.bvh"))}


def test_every_shared_clip_gives_a_rigid_symmetric_figure(shared_motions):
    assert len(shared_motions) >= 10
    for name, m in shared_motions.items():
        assert m.joints.shape == (m.n_frames, 17, 3), name
        assert np.all(np.isfinite(m.joints)), name
        assert_rigid(m)
        assert standing_height(m.class_lengths) == pytest.approx(1.75, rel=1e-12), name
        ankles = m.joints[:, [FEET["l"], FEET["r"]], 1]
        assert ankles.min() == pytest.approx(ANKLE_HEIGHT_FRACTION * 1.75, abs=1e-12), name
        assert m.contacts.shape == (m.n_frames, 2) and m.contacts.dtype == bool
        # plausible human: legs are longer than forearms, the head is above the pelvis on most frames
        c = m.class_lengths
        assert c[1] > c[9] and c[2] > c[9], name
        head_above = m.joints[:, JOINT_INDEX["head"], 1] > m.joints[:, JOINT_INDEX["pelvis"], 1]
        assert head_above.mean() > 0.9, name


def test_segment_directions_follow_the_clip(shared_bvh_dir):
    path = shared_bvh_dir / "131_03.bvh"
    motion = motion_from_bvh_file(path)
    source = canonical_positions(read_bvh(path))                     # Y-up already, no frame dropped
    assert motion.n_frames == source.shape[0]
    for parent, child in SEGMENTS:
        a = motion.joints[:, child] - motion.joints[:, parent]
        b = source[:, child] - source[:, parent]
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        b /= np.linalg.norm(b, axis=-1, keepdims=True)
        np.testing.assert_allclose(a, b, atol=1e-9)


def test_inserted_t_pose_is_dropped_only_where_present(shared_motions, shared_bvh_dir):
    assert shared_motions["01_01.bvh"].meta["dropped_first_frames"] == 1
    assert shared_motions["01_01.bvh"].n_frames == read_bvh(shared_bvh_dir / "01_01.bvh").n_frames - 1
    for name, m in shared_motions.items():
        if name != "01_01.bvh":
            assert m.meta["dropped_first_frames"] == 0, name


def test_walking_clips_have_alternating_contacts(shared_motions):
    for name in ("bandai_dataset-1_walk_normal_001.bvh", "neutral_01_000.bvh", "0005_Jogging001.bvh"):
        contacts = shared_motions[name].contacts
        assert 0.1 < contacts[:, 0].mean() < 0.9 and 0.1 < contacts[:, 1].mean() < 0.9, name
        single = contacts[:, 0] ^ contacts[:, 1]
        assert single.mean() > 0.2, name


def test_resampling_keeps_lengths_and_duration(shared_bvh_dir):
    path = shared_bvh_dir / "131_03.bvh"
    full = motion_from_bvh_file(path)
    slow = motion_from_bvh_file(path, fps=30, height_m=1.6)
    assert slow.fps == 30
    assert abs((slow.n_frames - 1) / 30 - (full.n_frames - 1) / full.fps) < 1 / 30
    assert_rigid(slow)
    assert standing_height(slow.class_lengths) == pytest.approx(1.6)
    np.testing.assert_allclose(slow.proportions, full.proportions, atol=1e-12)


def test_resample_is_linear():
    points = np.arange(5, dtype=float)[:, None] * np.array([1.0, 2.0])
    out = resample(points, 4.0, 8.0)
    np.testing.assert_allclose(out[:, 0], np.arange(9) / 2)


def test_load_motion_reads_bvh_and_truncates(shared_bvh_dir):
    m = load_motion(str(shared_bvh_dir / "bandai_dataset-1_walk_normal_001.bvh"), max_frames=40)
    assert m.n_frames == 40 and m.fps == pytest.approx(30.0)


def _small_walker(up: str):
    """A humanoid whose root translates (no joint rotations), standing along +Y or +Z."""
    tree = [("Hips", None, (0, 0, 0)),
            ("LeftUpLeg", "Hips", (9, -5, 0)), ("LeftLeg", "LeftUpLeg", (0, -43, 0)),
            ("LeftFoot", "LeftLeg", (0, -41, 0)), ("LeftFoot_End", "LeftFoot", (0, -5, 15)),
            ("RightUpLeg", "Hips", (-9, -5, 0)), ("RightLeg", "RightUpLeg", (0, -43, 0)),
            ("RightFoot", "RightLeg", (0, -41, 0)), ("RightFoot_End", "RightFoot", (0, -5, 15)),
            ("Spine", "Hips", (0, 12, 0)), ("Chest", "Spine", (0, 25, 0)), ("Neck", "Chest", (0, 16, 0)),
            ("Head", "Neck", (0, 10, 0)), ("Head_End", "Head", (0, 18, 0)),
            ("LeftArm", "Chest", (18, 10, 0)), ("LeftForeArm", "LeftArm", (28, 0, 0)),
            ("LeftHand", "LeftForeArm", (25, 0, 0)), ("LeftHand_End", "LeftHand", (8, 0, 0)),
            ("RightArm", "Chest", (-18, 10, 0)), ("RightForeArm", "RightArm", (-28, 0, 0)),
            ("RightHand", "RightForeArm", (-25, 0, 0)), ("RightHand_End", "RightHand", (-8, 0, 0))]
    n = 30
    root = np.stack([np.zeros(n), np.full(n, 100.0), np.linspace(0, 50, n)], axis=1)
    if up == "z":
        tree = [(name, parent, (o[0], -o[2], o[1])) for name, parent, o in tree]
        root = np.stack([root[:, 0], -root[:, 2], root[:, 1]], axis=1)
    bvh = make_bvh(tree)
    motion = np.zeros((n, bvh.motion.shape[1]))
    motion[:, :3] = root
    return make_bvh(tree, motion=motion)


def test_z_up_files_become_y_up(tmp_path):
    paths = {}
    for up in ("y", "z"):
        paths[up] = tmp_path / f"walker_{up}.bvh"
        paths[up].write_text(format_bvh(_small_walker(up)))
    y_up, z_up = motion_from_bvh_file(paths["y"]), motion_from_bvh_file(paths["z"])
    assert z_up.meta["up_axis"] == "z" and y_up.meta["up_axis"] == "y"
    np.testing.assert_allclose(z_up.joints, y_up.joints, atol=1e-6)
    head = y_up.joints[:, JOINT_INDEX["head"], 1]
    assert np.all(head > 1.6)
    assert y_up.joints[-1, 0, 2] - y_up.joints[0, 0, 2] > 0.3         # it travels along +Z


def test_bad_inputs(tmp_path):
    with pytest.raises(InputError):
        motion_from_bvh_file(tmp_path / "missing.bvh")
    path = tmp_path / "w.bvh"
    path.write_text(format_bvh(_small_walker("y")))
    with pytest.raises(InputError, match="height"):
        motion_from_bvh_file(path, height_m=0)
    with pytest.raises(InputError, match="fps"):
        motion_from_bvh_file(path, fps=-5)


def test_foot_contacts_low_and_slow():
    fps = 30.0
    n = 60
    walker = _small_walker("y")
    base = canonical_positions(walker)[0] / 100.0                                     # one standing pose, metres
    joints = np.repeat(base[None], n, axis=0)
    joints[..., 1] -= joints[:, [FEET["l"], FEET["r"]], 1].min() - 0.07
    lifted = np.zeros(n)
    lifted[20:40] = 0.25 * np.sin(np.linspace(0, np.pi, 20))        # left foot swings up and forward
    l_leg = [JOINT_INDEX["l_knee"], JOINT_INDEX["l_ankle"]]
    joints[:, l_leg, 1] += lifted[:, None] * np.array([0.5, 1.0])
    joints[:, l_leg, 2] += np.linspace(0, 0.5, n)[:, None] * (lifted[:, None] > 0)
    contacts = foot_contacts(joints, fps)
    assert contacts[:15, 0].all() and contacts[:, 1].all()
    assert not contacts[24:36, 0].any()
