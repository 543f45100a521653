"""The shared accuracy measures on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera import rotation_matrix
from core.evaluation import metrics


def test_proportion_errors_in_percentage_points():
    act = np.full(10, 0.1)
    est = act.copy()
    est[0], est[1] = 0.12, 0.08
    e = metrics.proportion_errors_pp(est, act)
    assert e["per_class"]["hip"] == pytest.approx(2.0) and e["per_class"]["thigh"] == pytest.approx(-2.0)
    assert e["mean_abs"] == pytest.approx(0.4) and e["max_abs"] == pytest.approx(2.0)


def test_spell_detection_counts_frames_and_boundaries():
    true = np.array([0, 0, 0, 1, 1, 1, 1, 0, 0, 0], bool)
    est = np.array([0, 0, 0, 0, 1, 1, 1, 1, 0, 0], bool)
    d = metrics.spell_detection(est, true, tolerance=1)
    assert d["frame_accuracy"] == pytest.approx(0.8)
    assert d["boundary_recall"] == 1.0 and d["boundary_offset_frames"] == pytest.approx(1.0)
    d0 = metrics.spell_detection(est, true, tolerance=0)
    assert d0["boundary_recall"] == 0.0


def test_stance_scale_and_focal():
    assert metrics.stance_accuracy(["l", "r", "r", None], ["l", "l", "r", "r"],
                                   np.array([1, 1, 1, 0], bool)) == pytest.approx(2 / 3)
    assert metrics.scale_error(np.array([1.0, 1.1]), np.array([1.0, 1.0])) == pytest.approx(0.05)
    assert metrics.focal_error_pct(51.0, 50.0) == pytest.approx(2.0)
    z = metrics.zoom_focal_error_pct(np.array([50.0, 55.0, 60.0]), np.array([50.0, 50.0, 50.0]),
                                     np.array([0, 1, 1], bool))
    assert z == pytest.approx(15.0)
    assert np.isnan(metrics.zoom_focal_error_pct(np.ones(3), np.ones(3), np.zeros(3, bool)))


def test_rotation_error_is_the_relative_angle():
    a = np.array([[0.0, 10.0, 0.0], [5.0, 0.0, 0.0]])
    b = np.array([[0.0, 12.0, 0.0], [5.0, 0.0, 1.0]])
    errs = metrics.rotation_errors_deg(a, b)
    assert errs[0] == pytest.approx(2.0, abs=1e-9)
    assert 0.9 < errs[1] < 1.1


def test_similarity_alignment_and_mpjpe():
    rng = np.random.default_rng(0)
    truth = rng.normal(size=(6, 17, 3))
    r = rotation_matrix(np.array([10.0, -20.0, 30.0]))
    est = 1.7 * truth @ r.T + np.array([1.0, 2.0, 3.0])
    assert metrics.mpjpe_per_frame_m(est, truth) < 1e-9
    assert metrics.mpjpe_clip_m(est, truth) < 1e-9
    noisy = truth + 0.01 * rng.normal(size=truth.shape)
    assert 0.005 < metrics.mpjpe_per_frame_m(noisy, truth) < 0.02
    # Per-frame alignment cannot be worse than one alignment for the whole clip.
    moved = noisy.copy()
    moved[3] += 0.5
    assert metrics.mpjpe_per_frame_m(moved, truth) < metrics.mpjpe_clip_m(moved, truth)


def test_followed_point_errors_split_where_a_track_sits_from_how_it_moves():
    from core.evaluation.metrics import followed_point_errors_px

    n = 10
    true = np.zeros((n, 2, 2))
    true[:, 0] = np.stack([np.arange(n) * 3.0, np.zeros(n)], axis=1) + [100.0, 100.0]
    true[:, 1] = np.stack([np.arange(n) * 3.0, np.zeros(n)], axis=1) + [400.0, 300.0]
    found = np.full((n, 3, 2), np.nan)
    found[:, 0] = true[:, 0] + [4.0, -3.0]                    # a corner 5 px off the point, moving with it
    found[2:, 1] = true[2:, 1]
    found[6:, 1] += [0.0, 2.0]                                # on the point, then slips 2 px
    gap, motion = followed_point_errors_px(found, true)
    np.testing.assert_allclose(gap[:2], [5.0, 0.0])
    np.testing.assert_allclose(motion[:2], [0.0, 2.0])
    assert np.isnan(gap[2]) and np.isnan(motion[2])          # never followed


# --- 3D motion measures -----------------------------------------------------------------------------

def _walk(n: int = 30) -> tuple[np.ndarray, float]:
    from core.synthetic.motion import load_motion

    m = load_motion("builtin:walk", max_frames=n)
    return np.asarray(m.joints, dtype=float), float(m.fps)


def _moved(x: np.ndarray, angle_deg: float = 30.0, scale: float = 1.3, shift=(0.4, -0.2, 3.0)) -> np.ndarray:
    return scale * x @ rotation_matrix(np.array([10.0, angle_deg, -5.0])).T + np.asarray(shift)


def test_mirrored_limb_frames_catch_a_depth_flipped_forearm_and_not_a_moved_figure():
    from core.skeleton import JOINT_INDEX

    truth, _ = _walk(4)
    truth = truth.copy()
    el, wr = JOINT_INDEX["l_elbow"], JOINT_INDEX["l_wrist"]
    truth[:, wr] = truth[:, el] + 0.25 * np.array([0.2, 0.0, 0.98])       # forearm pointing along depth
    est = truth.copy()
    est[2, wr] = est[2, el] + 0.25 * np.array([0.2, 0.0, -0.98])          # frame 2: mirrored in depth
    est = _moved(est)
    flags = metrics.mirrored_limb_frames(est, truth)
    assert flags.tolist() == [False, False, True, False]
    assert metrics.mirrored_limb_pct(est, truth) == pytest.approx(25.0)
    ang = metrics.limb_angles_deg(est, truth)
    assert ang.shape == (4, 8) and np.nanmax(ang[[0, 1, 3]]) < 1e-3
    assert ang[2].max() > 120.0
    # a forearm turned by 30 degrees is wrong but not mirrored
    turned = truth.copy()
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    d = truth[1, wr] - truth[1, el]
    turned[1, wr] = truth[1, el] + np.array([c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]])
    assert not metrics.mirrored_limb_frames(turned, truth)[1]


def test_depth_sign_errors_count_a_shallow_flip_in_each_frames_camera_axes():
    from core.skeleton import JOINT_INDEX

    truth, _ = _walk(4)
    truth = truth.copy()
    el, wr = JOINT_INDEX["l_elbow"], JOINT_INDEX["l_wrist"]
    k = metrics.LIMB_BONES.index((el, wr))
    # the forearm 30 degrees out of the picture in frames 0-2, in it in frame 3 (not scored)
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    truth[:3, wr] = truth[:3, el] + 0.25 * np.array([c, 0.0, s])
    truth[3, wr] = truth[3, el] + 0.25 * np.array([1.0, 0.0, 0.0])
    est = truth.copy()
    est[1, wr] = est[1, el] + 0.25 * np.array([c, 0.0, -s])      # frame 1: the other depth sign
    est[3, wr] = est[3, el] + 0.25 * np.array([c, 0.0, -s])      # frame 3: not scored
    zero = np.zeros((4, 3))
    err = metrics.depth_sign_error_pct(est, truth, zero, zero)
    assert err[k] == pytest.approx(100.0 / 3.0)
    assert metrics.limb_angles_deg(est, truth)[1, k] < 70.0          # wrong, yet not a mirrored limb by angle
    # the same figure filmed by a turned camera: the depth is the camera's, so turning both changes nothing,
    # while turning only the estimate's camera by 90 degrees about the vertical swaps depth for across
    turn = np.tile([0.0, 90.0, 0.0], (4, 1))
    turned = est @ rotation_matrix(np.array([0.0, -90.0, 0.0])).T
    assert metrics.depth_sign_error_pct(turned, truth, turn, zero)[k] == pytest.approx(100.0 / 3.0)
    assert metrics.depth_sign_error_pct(est, truth, turn, zero)[k] != pytest.approx(100.0 / 3.0)


def test_planted_foot_speed_measures_the_estimated_ankle_sliding_while_the_true_one_stands():
    from core.skeleton import FEET

    n, fps = 20, 30.0
    truth = np.zeros((n, 17, 3))
    truth += np.arange(17)[None, :, None] * 0.1        # distinct static joints
    est = truth.copy()
    est[:, FEET["l"], 0] += 0.05 * np.arange(n) / fps   # slides at 50 mm/s
    planted = np.zeros((n, 2), bool)
    planted[5:15, 0] = True
    r = metrics.planted_foot_speed_mm_s(est, truth, fps, planted)
    assert r["estimated_mm_s"] == pytest.approx(50.0) and r["true_mm_s"] == pytest.approx(0.0)
    assert r["excess_mm_s"] == pytest.approx(50.0) and r["n"] == 10
    # the right ankle is not planted anywhere: its speed does not count
    assert metrics.planted_foot_speed_mm_s(truth, truth, fps, planted)["excess_mm_s"] == pytest.approx(0.0)
    assert metrics.planted_foot_speed_mm_s(est, truth, fps, np.zeros((n, 2), bool))["n"] == 0


def test_planted_masks_from_the_stance_and_from_the_true_speed():
    p = metrics.planted_from_stance(["l", "l", None, "r"])
    assert p.tolist() == [[True, False], [True, False], [False, False], [False, True]]
    walk, fps = _walk(60)
    sp = metrics.planted_from_speed(walk, fps, 0.1)
    assert sp.shape == (60, 2) and sp.any() and not sp.all()


def test_acceleration_error_is_zero_for_a_moved_copy_and_counts_jitter():
    walk, fps = _walk(40)
    moved = _moved(walk)
    assert metrics.acceleration_error_mm_s2(moved, walk, fps, "clip") < 1e-6
    assert metrics.acceleration_error_mm_s2(moved, walk, fps, "frame") < 1e-6
    # one joint shaking +-1 mm in depth every frame: |second difference| = 4 mm a frame^2, over 17 joints
    shaky = walk.copy()
    shaky[:, 0, 2] += 0.001 * (-1.0) ** np.arange(40)
    expect = 4.0 * fps * fps / 17.0
    assert metrics.acceleration_error_mm_s2(shaky, walk, fps, "clip") == pytest.approx(expect, rel=0.05)
    with pytest.raises(ValueError):
        metrics.acceleration_error_mm_s2(shaky, walk, fps, "world")


def test_per_frame_mpjpe_list_matches_the_mean():
    walk, _ = _walk(10)
    est = walk.copy()
    est[3, 5] += np.array([0.0, 0.17, 0.0])
    per = metrics.mpjpe_frames_m(est, walk)
    assert per.shape == (10,) and per[0] < 1e-9 and per[3] > 0.005
    assert float(np.mean(per)) == pytest.approx(metrics.mpjpe_per_frame_m(est, walk))


def test_the_rigid_clip_alignment_keeps_the_estimates_size():
    walk, fps = _walk(40)
    # the walk placed twice as far and twice as large, as a lens twice too long puts it: a similarity undoes
    # it whole, a rigid alignment keeps its doubled jitter-free path, whose accelerations are twice the truth's
    doubled = 2.0 * walk
    assert metrics.acceleration_error_mm_s2(doubled, walk, fps, "clip") < 1e-6
    rigid = metrics.acceleration_error_mm_s2(doubled, walk, fps, "clip-rigid")
    true_acc = np.nanmean(np.linalg.norm(walk[2:] - 2 * walk[1:-1] + walk[:-2], axis=-1)) * fps * fps * 1000
    assert rigid == pytest.approx(true_acc, rel=1e-6) and rigid > 100.0
    turned = _moved(walk, scale=1.0)                        # turned and moved, its size kept
    assert metrics.acceleration_error_mm_s2(turned, walk, fps, "clip-rigid") < 1e-6
