"""Motion cleanup: contacts read from the motion, planted ankles pinned, legs kept whole, no pop at release."""

from __future__ import annotations

import numpy as np
import pytest

from core.evaluation import metrics
from core.motion_cleanup import CleanupSettings, clean_motion, detect_contacts
from core.motion_cleanup.foot_lock import LEGS, two_bone_ik
from core.runs import runs
from core.skeleton import FEET
from core.synthetic.motion import load_motion
from core.synthetic.synth import YUP_TO_BLENDER

#: the motion's Y-up world -> Z-up world, as the joint solve's world_from_cam0 gives it
WORLD = np.eye(4)
WORLD[:3, :3] = YUP_TO_BLENDER


def _walk(seconds: float = 6.0, fps: float = 30.0):
    m = load_motion("builtin:walk", fps=fps, max_frames=int(seconds * fps))
    return np.asarray(m.joints, dtype=float), np.asarray(m.contacts, dtype=bool), float(m.fps)


def _sliding(joints: np.ndarray, fps: float, seed: int = 0) -> np.ndarray:
    """The walk as a solve leaves it: ankles (and their knees) drifting and shaking by a few mm a frame."""
    rng = np.random.default_rng(seed)
    out = joints.copy()
    for s in ("l", "r"):
        drift = np.cumsum(rng.normal(0.0, 0.002, (joints.shape[0], 3)), axis=0)
        out[:, FEET[s]] += drift + rng.normal(0.0, 0.003, (joints.shape[0], 3))
    return out


def _leg_lengths(j: np.ndarray) -> np.ndarray:
    return np.stack([np.linalg.norm(j[:, k] - j[:, h], axis=-1) for h, k, _ in LEGS.values()] +
                    [np.linalg.norm(j[:, a] - j[:, k], axis=-1) for _, k, a in LEGS.values()], axis=1)


def _release_pop(raw: np.ndarray, clean: np.ndarray, fps: float) -> float:
    """Largest extra frame-to-frame ankle step (m) the cleanup adds in the 5 frames after a contact ends."""
    found = detect_contacts(raw @ YUP_TO_BLENDER.T, fps, 1.75)
    pop = 0.0
    for si, s in enumerate("lr"):
        a = FEET[s]
        extra = np.linalg.norm(np.diff(clean[:, a], axis=0) - np.diff(raw[:, a], axis=0), axis=-1)
        for _, end in runs(found[:, si]):
            pop = max(pop, float(extra[end - 1:end + 4].max(initial=0.0)))
    return pop


def test_contacts_from_the_motion_agree_with_the_walks_truth():
    joints, contacts, fps = _walk()
    found = detect_contacts(joints @ YUP_TO_BLENDER.T, fps, 1.75)
    agree = (found == contacts).mean()
    assert agree > 0.85, agree
    # every contact lasts at least the minimum time
    for s in range(2):
        assert all(end - a >= round(0.1 * fps) for a, end in runs(found[:, s]))


def test_two_bone_ik_reaches_a_reachable_goal_and_keeps_the_bones():
    hip = np.array([[0.0, 1.0, 0.0]])
    knee = np.array([[0.05, 0.55, 0.1]])
    ankle = np.array([[0.0, 0.1, 0.0]])
    goal = np.array([[0.1, 0.15, 0.05]])
    k2, a2 = two_bone_ik(hip, knee, ankle, goal)
    assert np.allclose(a2, goal)
    assert np.linalg.norm(k2 - hip) == pytest.approx(np.linalg.norm(knee - hip))
    assert np.linalg.norm(a2 - k2) == pytest.approx(np.linalg.norm(ankle - knee))
    # out of reach: as near as the straight leg gets
    far = np.array([[0.0, -2.0, 0.0]])
    _, a3 = two_bone_ik(hip, knee, ankle, far)
    reach = np.linalg.norm(knee - hip) + np.linalg.norm(ankle - knee)
    assert np.linalg.norm(a3 - hip) == pytest.approx(reach, abs=1e-5)


def test_locked_feet_are_slower_while_planted_keep_their_bones_and_do_not_pop():
    joints, contacts, fps = _walk()
    raw = _sliding(joints, fps)
    clean, report = clean_motion(raw, WORLD, fps, 1.75, CleanupSettings())
    assert sum(report["contacts"]) >= 6
    planted = metrics.planted_from_speed(joints, fps, 0.1) & contacts
    before = metrics.planted_foot_speed_mm_s(raw, joints, fps, planted)
    after = metrics.planted_foot_speed_mm_s(clean, joints, fps, planted)
    assert after["estimated_mm_s"] < 0.5 * before["estimated_mm_s"], (before, after)
    assert abs(after["excess_mm_s"]) < abs(before["excess_mm_s"])
    # bone lengths of both legs kept on every frame
    assert np.allclose(_leg_lengths(clean), _leg_lengths(raw), atol=1e-9)
    # no pop at release: over the frames after each contact the lock adds at most 6 mm to the ankle's
    # frame-to-frame step; without the easing the same walk jumps by more
    assert _release_pop(raw, clean, fps) < 0.006
    sudden, _ = clean_motion(raw, WORLD, fps, 1.75, CleanupSettings(blend_s=0.0))
    assert _release_pop(raw, sudden, fps) > 0.008
    # the lock moved nothing but the legs
    others = [i for i in range(17) if i not in {k for leg in LEGS.values() for k in leg[1:]}]
    assert np.array_equal(clean[:, others], raw[:, others])


def test_the_lock_off_and_the_root_smoothing_keep_the_figure_rigid():
    joints, _, fps = _walk(3.0)
    raw = _sliding(joints, fps) + np.array([0.0, 0.0, 6.0])
    same, _ = clean_motion(raw, WORLD, fps, 1.75, CleanupSettings(lock_feet=False, root_sigma_s=0.0))
    assert np.array_equal(same, raw)
    shaky = raw * (1.0 + 0.01 * np.random.default_rng(1).normal(size=(raw.shape[0], 1, 1)))
    smooth, rep = clean_motion(shaky, WORLD, fps, 1.75, CleanupSettings(lock_feet=False, root_sigma_s=0.1))
    assert rep["root_max_slide_m"] > 0.01
    # every joint moved by the same vector in a frame (a rigid slide), along the pelvis' ray
    move = smooth - shaky
    assert np.allclose(move, move[:, :1], atol=1e-12)
    ray = shaky[:, 0] / np.linalg.norm(shaky[:, 0], axis=-1, keepdims=True)
    assert np.allclose(np.cross(move[:, 0], ray), 0.0, atol=1e-12)


def test_the_joint_method_holds_planted_feet_end_to_end():
    from core.estimate import estimate
    from core.synthetic.synth import synthesize

    motion = load_motion("builtin:walk", max_frames=120)
    tracks, truth = synthesize(motion, noise_px=1.0, seed=3)
    raw = estimate(tracks, "joint", motion_cleanup=None)
    clean = estimate(tracks, "joint")
    assert "motion_cleanup" in clean.diagnostics and "motion_cleanup" not in raw.diagnostics
    jr = np.array([f.joints_3d for f in raw.frames])
    jc = np.array([f.joints_3d for f in clean.frames])
    planted = metrics.planted_from_stance(truth.stance) & metrics.planted_from_speed(truth.joints_3d, truth.fps)
    before = metrics.planted_foot_speed_mm_s(jr, truth.joints_3d, truth.fps, planted)
    after = metrics.planted_foot_speed_mm_s(jc, truth.joints_3d, truth.fps, planted)
    assert after["estimated_mm_s"] < 0.7 * before["estimated_mm_s"], (before, after)
    # the legs keep their lengths, the pose is no worse, the picture is still explained
    assert np.allclose(_leg_lengths(jc), _leg_lengths(jr), atol=1e-6)
    assert metrics.mpjpe_per_frame_m(jc, truth.joints_3d) < metrics.mpjpe_per_frame_m(jr, truth.joints_3d) + 0.003
    rr = np.mean([f.reprojection_px for f in raw.frames])
    rc = np.mean([f.reprojection_px for f in clean.frames])
    assert rc < rr + 0.5, (rr, rc)
