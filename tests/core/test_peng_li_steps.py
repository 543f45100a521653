"""Each step of the Peng & Li pipeline pinned on hand-made geometry or synthetic truth."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera import pan_tilt_roll_matrix, pixels_to_film, project_to_film
from core.joint_solve.stance import stance_codes
from core.peng_li.camera_motion import (
    estimate_spell_models,
    rotation_increments,
    smoothness_pairwise,
    solve_pan_tilt,
    track_rotation,
    track_zoom,
)
from core.peng_li.lower_bounds import child_candidates, distance_to_ray, frame_lower_bounds, rays
from core.peng_li.params import PAPER, PaperParams
from core.peng_li.rectify import fill_short_gaps, rectify, savgol
from core.peng_li.segmentation import segment
from core.peng_li.stance import sequence_cost, stance_brute_force, stance_dp, valid_sequence
from core.peng_li.undo_camera import camera_rotations, redo_camera, undo_camera
from core.peng_li.virtual_scale import virtual_scale
from core.skeleton import FEET, SEGMENTS, segment_lengths
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize

FEET_IDX = [FEET["l"], FEET["r"]]


@pytest.fixture(scope="module")
def walk():
    motion = load_motion("builtin:walk", fps=30.0)
    clean = synthesize(motion, noise_px=0.0, seed=0)
    noisy = synthesize(motion, noise_px=1.0, seed=0)
    return motion, clean, noisy


def film(tracks):
    return pixels_to_film(tracks.xy, tracks.image_size)


# --- step 1: rectification --------------------------------------------------------------------

def test_short_gaps_are_bridged_long_gaps_stay_missing():
    s = np.arange(40, dtype=float)
    s[5:8] = np.nan
    s[20:35] = np.nan
    out = fill_short_gaps(s, max_gap=5)
    assert np.allclose(out[5:8], [5, 6, 7])
    assert np.isnan(out[20:35]).all()


def test_smoothing_removes_most_noise_of_a_smooth_trajectory():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 3, 90)
    clean = np.stack([np.sin(t), np.cos(0.5 * t)], axis=-1)[:, None, :].repeat(17, axis=1)
    noisy = clean + rng.normal(0, 0.02, clean.shape)
    out = rectify(noisy, 30.0, PAPER)
    assert np.sqrt(np.mean((out - clean) ** 2)) < 0.6 * np.sqrt(np.mean((noisy - clean) ** 2))


@pytest.mark.parametrize("n, window, order", [(90, 11, 2), (11, 11, 2), (40, 5, 1), (40, 21, 3), (3, 3, 1)])
def test_savgol_matches_scipys_savitzky_golay_with_fitted_ends(n, window, order):
    from scipy.signal import savgol_filter

    y = np.random.default_rng(n + window).normal(size=n).cumsum()
    assert np.allclose(savgol(y, window, order), savgol_filter(y, window, order, mode="interp"), atol=1e-10)


def test_savgol_keeps_a_polynomial_of_its_degree():
    t = np.arange(30.0)
    y = 0.5 - 0.2 * t + 0.03 * t ** 2
    assert np.allclose(savgol(y, 7, 2), y, atol=1e-9)


# --- step 2: segmentation ------------------------------------------------------------------------

def test_segmentation_finds_the_moving_spells(walk):
    _, (tracks, truth), _ = walk
    feet = rectify(film(tracks), tracks.fps, PAPER)[:, FEET_IDX]
    spells = segment(feet, tracks.fps, PAPER.still_threshold_px_per_frame * 0.05, PAPER)  # noise-free: base threshold
    moving = np.zeros(tracks.n_frames, dtype=bool)
    for sp in spells:
        moving[sp.start:sp.end + 1] = sp.moving
    assert np.mean(moving == truth.camera_moving) > 0.88
    n_true = sum(1 for s in truth.spells if s.moving)
    assert sum(1 for s in spells if s.moving) == n_true
    # Every true motion overlaps a detected one.
    for s in truth.spells:
        if s.moving:
            assert moving[s.start:s.end + 1].mean() > 0.5


# --- step 3: stance foot, dynamic programme vs the paper's enumeration ----------------------------

def test_dp_matches_brute_force_on_random_costs():
    rng = np.random.default_rng(3)
    for _ in range(25):
        n, m = int(rng.integers(5, 26)), int(rng.integers(3, 7))
        unary, pairwise = rng.random((n, 2)), rng.random((n, 2, 2))
        a = stance_dp(unary, pairwise, m)
        b = stance_brute_force(unary, pairwise, m)
        assert valid_sequence(a, m)
        assert sequence_cost(a, unary, pairwise) == pytest.approx(sequence_cost(b, unary, pairwise), abs=1e-12)


def test_dp_matches_brute_force_and_truth_on_a_camera_spell(walk):
    _, (tracks, truth), _ = walk
    spell = next(s for s in truth.spells if s.kind == "pan")
    a, b = spell.start, min(spell.end, spell.start + 34)
    feet = rectify(film(tracks), tracks.fps, PAPER)[a:b + 1][:, FEET_IDX]
    pairwise = smoothness_pairwise(rotation_increments(feet, 50.0))
    unary = np.zeros((feet.shape[0], 2))
    m = PAPER.window_frames(PAPER.min_stance_s, tracks.fps)
    dp = stance_dp(unary, pairwise, m)
    bf = stance_brute_force(unary, pairwise, m)
    assert np.array_equal(dp, bf)
    clear = truth.stance_clear[a:b + 1]
    true = stance_codes(truth.stance[a:b + 1])
    assert np.mean(dp[clear] == true[clear]) > 0.85


# --- step 4: camera motion and undoing it ----------------------------------------------------------

def test_pan_tilt_solution_is_exact():
    rng = np.random.default_rng(1)
    for _ in range(50):
        pan, tilt = rng.uniform(-25, 25), rng.uniform(-10, 10)
        w = np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.4), 1.0])
        p, t = solve_pan_tilt(w, pan_tilt_roll_matrix(pan, tilt) @ w, 0.0)
        assert p == pytest.approx(pan, abs=1e-8) and t == pytest.approx(tilt, abs=1e-8)


def _static_feet(n, swap):
    """Two planted feet in frame-0 camera coordinates (metres); stance swaps at frame ``swap``."""
    left = np.array([-0.1, 0.9, 5.0])
    right = np.array([0.25, 0.92, 5.3])
    stance = np.where(np.arange(n) < swap, 0, 1)
    return left, right, stance


def test_rotation_recovered_from_the_stance_foot():
    n = 40
    pan = 12.0 * (1 - np.cos(np.pi * np.arange(n) / (n - 1))) / 2
    tilt = -4.0 * (1 - np.cos(np.pi * np.arange(n) / (n - 1))) / 2
    left, right, stance = _static_feet(n, 20)
    rot = pan_tilt_roll_matrix(pan, tilt)
    feet = np.stack([project_to_film(rot @ left, 50.0), project_to_film(rot @ right, 50.0)], axis=1)
    p, t = track_rotation(feet, stance, 50.0, 0.0, 0.0)
    assert np.allclose(p, pan, atol=1e-6) and np.allclose(t, tilt, atol=1e-6)
    best = min(estimate_spell_models(feet, 50.0, 0.0, 0.0, 10), key=lambda r: r.cost)
    assert best.model == "rotate"


def test_zoom_recovered_from_the_stance_foot():
    n = 40
    focal = 50.0 * 1.3 ** ((1 - np.cos(np.pi * np.arange(n) / (n - 1))) / 2)
    left, right, stance = _static_feet(n, 25)
    feet = np.stack([project_to_film(np.tile(left, (n, 1)), focal),
                     project_to_film(np.tile(right, (n, 1)), focal)], axis=1)
    f = track_zoom(feet, stance, 50.0)
    assert np.allclose(f, focal, rtol=1e-9)


def test_undo_gives_the_static_camera_view(walk):
    _, (tracks, truth), _ = walk
    rot = truth.rotations()
    static = undo_camera(film(tracks), rot, truth.focal_mm, float(truth.focal_mm[0]))
    expected = project_to_film(truth.joints_3d, float(truth.focal_mm[0]))
    ok = np.isfinite(static).all(axis=-1)
    assert np.abs(static[ok] - expected[ok]).max() < 1e-6
    back = redo_camera(static, rot, truth.focal_mm, float(truth.focal_mm[0]))
    assert np.abs(back[ok] - film(tracks)[ok]).max() < 1e-9


def test_camera_rotations_match_core_convention():
    r = camera_rotations(np.array([10.0]), np.array([-3.0]))[0]
    assert np.allclose(r, pan_tilt_roll_matrix(10.0, -3.0))


# --- step 5: virtual scale ---------------------------------------------------------------------

def test_virtual_scale_close_to_truth(walk):
    _, (tracks, truth), _ = walk
    static = project_to_film(truth.joints_3d, float(truth.focal_mm[0]))
    stance = stance_codes(truth.stance)
    scale, info = virtual_scale(static, stance, 6)
    assert scale[0] == 1.0
    assert len(info["swap_frames"]) >= 10
    assert np.mean(np.abs(scale / truth.scale - 1.0)) < 0.04


# --- step 6: lower bounds ------------------------------------------------------------------------

def _figure_frames(rng, n):
    """Random rigid poses of a 17-joint figure (camera coordinates, metres) and its segment lengths."""
    motion = load_motion("builtin:walk", fps=30.0)
    base = motion.joints[::7][:n]
    out = []
    for pose in base:
        r = pan_tilt_roll_matrix(rng.uniform(-60, 60), rng.uniform(-20, 20), rng.uniform(-10, 10))
        p = (pose - pose[0]) @ r.T
        out.append(p + np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3), rng.uniform(4, 8)]))
    return np.array(out), segment_lengths(motion.joints[0])


def test_lower_bounds_never_exceed_truth_and_are_exact_when_perpendicular():
    rng = np.random.default_rng(5)
    joints, lengths = _figure_frames(rng, 30)
    # Frame 0: the left hip segment parallel to the image plane with the hip joint on the optical
    # axis, so the segment is also perpendicular to the hip's viewing ray.
    j0 = joints[0] - joints[0][0]
    v = j0[5].copy()
    v[2] = 0.0
    j0[5] = v / np.linalg.norm(v) * lengths[4]
    joints[0] = j0 - j0[5] + np.array([0.0, 0.0, 6.0])
    f = 50.0
    pts = project_to_film(joints, f)
    depth = joints[:, 0, 2]   # pelvis depth
    scale = depth[0] / depth                       # true virtual scale s'
    true_virtual = lengths * f / depth[0]          # normalised lengths (frame-0 virtual figure)
    bounds, est = frame_lower_bounds(pts, f, scale, lengths=true_virtual)
    assert np.all(bounds[np.isfinite(bounds)] <= np.repeat(true_virtual[None], 30, 0)[np.isfinite(bounds)] + 1e-9)
    for k, (_, child) in enumerate(SEGMENTS):
        if child == 5:   # the left hip: exact in frame 0
            assert est[k] == pytest.approx(true_virtual[k], rel=1e-9)
            assert bounds[0, k] == pytest.approx(true_virtual[k], rel=1e-9)


def test_second_level_branches_contain_the_true_joint_and_give_an_exact_bound():
    # pelvis -> hip -> knee, the knee segment perpendicular to the knee's viewing ray.
    pelvis = np.array([0.0, 0.0, 5.0])
    hip = np.array([0.1, 0.05, 5.02])
    u = np.array([0.2, 0.5, 5.0]) / np.linalg.norm([0.2, 0.5, 5.0])
    knee = np.dot(hip, u) * u                  # the point of the knee's ray nearest the hip
    f = 50.0
    pts = project_to_film(np.stack([pelvis, hip, knee])[None], f)[0]
    k = f / pelvis[2]                          # virtual figure: pelvis on the image plane
    cands = child_candidates(np.array([[[pts[0, 0], pts[0, 1], f]]]), rays(pts[1][None], f),
                             np.array([np.linalg.norm(hip - pelvis) * k]))
    assert np.min(np.linalg.norm(cands[0] - hip * k, axis=-1)) < 1e-9
    bound = distance_to_ray(cands, rays(pts[2][None], f))[0]
    assert np.min(np.abs(bound - np.linalg.norm(knee - hip) * k)) < 1e-9
    assert bound.min() <= np.linalg.norm(knee - hip) * k + 1e-12


def test_paper_params_have_the_papers_defaults():
    p = PaperParams()
    assert p.still_window_s == 0.5 and p.bound_quantile == 1.0
    assert p.window_frames(p.still_window_s, 30.0) == 15
