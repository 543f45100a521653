"""Perspective Taylor construction, the sign DP and the floor plane (core.joint_solve)."""

import itertools

import numpy as np
import pytest

from core.joint_solve import ground, signs_dp, taylor
from core.motion import load_motion
from core.skeleton import FEET, SEGMENT_CLASS, SEGMENTS
from core.synth import synthesize


@pytest.fixture(scope="module")
def clip():
    motion = load_motion("builtin:walk", max_frames=60, fps=30.0)
    tracks, truth = synthesize(motion, kinds=("pan", "tilt", "zoom"), noise_px=0.0, seed=3, continuous=True)
    return tracks, truth


def _true_signs(rays, joints_cam, lengths):
    seg_len = np.asarray(lengths)[list(SEGMENT_CLASS)]
    signs = np.zeros((rays.shape[0], len(SEGMENTS)))
    for s, (p, c) in enumerate(SEGMENTS):
        near, far, _ = taylor.child_candidates(joints_cam[:, p], rays[:, c], seg_len[s])
        d_far = np.linalg.norm(far - joints_cam[:, c], axis=-1)
        d_near = np.linalg.norm(near - joints_cam[:, c], axis=-1)
        signs[:, s] = np.where(d_far < d_near, 1.0, -1.0)
    return signs


def test_both_roots_lie_on_the_ray_at_the_segment_length():
    rng = np.random.default_rng(0)
    parent = rng.normal(size=(50, 3)) + np.array([0, 0, 6.0])
    ray = rng.normal(size=(50, 3)) * 0.05 + np.array([0, 0, 1.0])
    ray /= np.linalg.norm(ray, axis=-1, keepdims=True)
    length = 5.0
    near, far, short = taylor.child_candidates(parent, ray, length)
    ok = short == 0
    assert ok.sum() > 10
    for cand in (near, far):
        assert np.allclose(np.linalg.norm(cand[ok] - parent[ok], axis=-1), length)
        assert np.allclose(np.cross(cand, ray), 0.0, atol=1e-9)
    assert np.all(far[ok, 2] >= near[ok, 2])


def test_reconstruct_with_true_signs_is_exact(clip):
    tracks, truth = clip
    cam = truth.joints_camera()
    rays = taylor.unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    signs = _true_signs(rays, cam, truth.class_lengths_m)
    rec = taylor.reconstruct(rays, truth.class_lengths_m, cam[:, 0, 2], signs)
    assert np.abs(rec - cam).max() < 1e-6


def test_viterbi_matches_brute_force():
    rng = np.random.default_rng(1)
    n, s = 6, 4
    for _ in range(5):
        unary = rng.random((n, s)) * 3
        pair = rng.random((n - 1, s, s)) * 3
        path = signs_dp.viterbi(unary, pair)

        def cost(seq, unary=unary, pair=pair):
            return unary[np.arange(n), seq].sum() + sum(pair[i, seq[i], seq[i + 1]] for i in range(n - 1))

        best = min(itertools.product(range(s), repeat=n), key=lambda q: cost(np.array(q)))
        assert cost(path) == pytest.approx(cost(np.array(best)))


def test_dp_signs_recover_the_pose_without_noise(clip):
    tracks, truth = clip
    cam = truth.joints_camera()
    rays = taylor.unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    _, joints = signs_dp.resolve_signs(rays, truth.class_lengths_m, cam[:, 0, 2], truth.rotations())
    err = np.linalg.norm(joints - cam, axis=-1)
    legs = [FEET["l"], FEET["r"], FEET["l"] - 1, FEET["r"] - 1]
    # legs decide facing; the knees' bending direction must get them right
    assert np.median(err[:, legs]) < 0.02
    assert np.median(err) < 0.05


def test_knee_hinge_violation_sign():
    left = np.array([[1.0, 0, 0]])
    up = np.array([[0, -1.0, 0]])               # camera axes: y down
    fwd = np.cross(left, up)
    thigh = -up * 0.45
    shank_back = -up * 0.4 - fwd * 0.2
    shank_front = -up * 0.4 + fwd * 0.2
    assert signs_dp.hinge_violation(thigh, shank_back, left, 1.0)[0] == 0.0
    assert signs_dp.hinge_violation(thigh, shank_front, left, 1.0)[0] > 0.1


def test_ground_from_planted_feet_matches_truth(clip):
    _, truth = clip
    code = {"l": 0, "r": 1}
    stance = np.array([code.get(s, -1) for s in truth.stance])
    m, _ = ground.world_from_cam0(truth.joints_3d, stance, truth.height_m)
    up_est = m[2, :3]
    up_true = np.asarray(truth.world_from_cam0)[2, :3]
    angle = np.degrees(np.arccos(np.clip(up_est @ up_true / np.linalg.norm(up_true), -1, 1)))
    assert angle < 3.0
    # planted ankles sit at ankle height above the floor
    world = truth.joints_3d @ m[:3, :3].T + m[:3, 3]
    planted = np.concatenate([world[stance == 0, FEET["l"], 2], world[stance == 1, FEET["r"], 2]])
    assert np.median(planted) == pytest.approx(0.039 * truth.height_m, abs=0.02)
    assert np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9)
