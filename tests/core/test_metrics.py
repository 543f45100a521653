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
