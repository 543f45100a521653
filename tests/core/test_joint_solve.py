"""The joint least-squares solve and the "joint" method end to end (core.joint_solve)."""

import dataclasses

import numpy as np
import pytest

from core import camera as cam
from core.errors import Cancelled, InputError
from core.estimate import estimate
from core.evaluation.metrics import proportion_errors_pp, rotation_error_deg
from core.joint_solve import calibration
from core.joint_solve import solver as slv
from core.joint_solve.pipeline import estimate_joint
from core.joint_solve.stance import stance_codes
from core.skeleton import N_JOINTS
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.tracks import Tracks


def _clip(n, noise, **kw):
    motion = load_motion("builtin:walk", max_frames=n, fps=30.0)
    return synthesize(motion, kinds=("pan", "tilt", "zoom"), noise_px=noise, seed=1, continuous=True, **kw)


def test_analytic_jacobian_matches_finite_differences(check_cost_gradient):
    tracks, truth = _clip(8, 1.0, dropout=0.1)
    film = cam.pixels_to_film(tracks.xy, tracks.image_size)
    st = stance_codes(truth.stance)
    # the knee, head, spine and symmetry priors hold a reference direction constant within a step: off here
    sig = slv.Sigmas(knee=1e9, head_align=1e9, spine_straight=1e9, symmetry_m=1e9)
    prob = slv.Problem(film, cam.mm_per_pixel(tracks.image_size), tracks.fps, 1.75, st, sigmas=sig,
                       focal_prior_mm=50.0)
    rng = np.random.default_rng(0)
    x = slv.pack(truth.joints_3d + rng.normal(0, 0.01, truth.joints_3d.shape), np.radians(truth.rotvec_deg) + 0.01,
                 np.log(truth.focal_mm), truth.class_lengths_m, stance=st)
    check_cost_gradient(prob, x, rng.choice(x.size, 60, replace=False), eps=1e-6, rel=2e-3, abs_scale=2e-2)


def test_bone_cue_jacobian_matches_finite_differences(check_cost_gradient):
    """The depth cue's residuals (each bone's unit vector in the frame's camera axes against a direction)
    move with the joints and the camera's rotation; their analytic derivatives agree with the cost's."""
    tracks, truth = _clip(8, 1.0)
    film = cam.pixels_to_film(tracks.xy, tracks.image_size)
    st = stance_codes(truth.stance)
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(8, 16, 3))
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    dirs[2, 5] = np.nan                                   # no cue for one bone of one frame
    sig = slv.Sigmas(knee=1e9, head_align=1e9, spine_straight=1e9, symmetry_m=1e9)
    prob = slv.Problem(film, cam.mm_per_pixel(tracks.image_size), tracks.fps, 1.75, st, sigmas=sig,
                       focal_prior_mm=50.0, bone_cue={"dirs": dirs, "sigma": 0.3})
    x = slv.pack(truth.joints_3d + rng.normal(0, 0.01, truth.joints_3d.shape), np.radians(truth.rotvec_deg) + 0.01,
                 np.log(truth.focal_mm), truth.class_lengths_m, stance=st)
    parts: dict = {}
    slv.residuals(prob, x, False, parts)
    assert parts["bone_cue"] > 0
    check_cost_gradient(prob, x, rng.choice(x.size, 60, replace=False), eps=1e-6, rel=2e-3, abs_scale=2e-2)


def test_standing_terms_jacobian_matches_finite_differences(check_cost_gradient):
    """A person standing on the spot: the hips' acceleration and each ankle held where it stands (robustly,
    so some of its changes are past the Huber threshold) agree with the cost's derivatives."""
    tracks, truth = _clip(8, 1.0)
    film = cam.pixels_to_film(tracks.xy, tracks.image_size)
    st = stance_codes(truth.stance)
    rng = np.random.default_rng(2)
    feet = np.ones((8, 2), dtype=bool)
    feet[3:5, 1] = False
    sig = slv.Sigmas(knee=1e9, head_align=1e9, spine_straight=1e9, symmetry_m=1e9)
    prob = slv.Problem(film, cam.mm_per_pixel(tracks.image_size), tracks.fps, 1.75, st, sigmas=sig,
                       focal_prior_mm=50.0, standing={"accel_ms2": 2.5, "feet": feet})
    x = slv.pack(truth.joints_3d + rng.normal(0, 0.01, truth.joints_3d.shape), np.radians(truth.rotvec_deg) + 0.01,
                 np.log(truth.focal_mm), truth.class_lengths_m, stance=st)
    parts: dict = {}
    slv.residuals(prob, x, False, parts)
    assert parts["standing"] > 0
    without: dict = {}
    slv.residuals(dataclasses.replace(prob, standing=None), x, False, without)
    assert "standing" not in without
    cols = np.concatenate([rng.choice(x.size, 40, replace=False),
                           [f * slv.BLOCK + j * 3 + a for f in (2, 4) for j in (0, 5, 7, 8, 10) for a in range(3)]])
    check_cost_gradient(prob, x, cols, eps=1e-6, rel=2e-3, abs_scale=2e-2)


def test_zero_noise_solve_recovers_lengths_and_camera():
    """Noise-free, started 3 % off in lengths and 1 cm off in joints, frame 0's focal known.

    The focal length itself is pinned (tight prior): 6 m away the clip has so little perspective
    that f trades against depth and the metric priors would bias it (measured: 6-10 % off).
    """
    tracks, truth = _clip(60, 0.0)
    film = cam.pixels_to_film(tracks.xy, tracks.image_size)
    st = stance_codes(truth.stance)
    prob = slv.Problem(film, cam.mm_per_pixel(tracks.image_size), tracks.fps, truth.height_m, st,
                       focal_prior_mm=float(truth.focal_mm[0]), focal_prior_sigma=0.002)
    rng = np.random.default_rng(2)
    lengths0 = truth.class_lengths_m * (1 + rng.normal(0, 0.03, 10))
    x0 = slv.pack(truth.joints_3d + rng.normal(0, 0.01, truth.joints_3d.shape), np.radians(truth.rotvec_deg),
                  np.log(truth.focal_mm) + 0.01, lengths0, stance=st)
    x, rep = slv.solve(prob, x0, max_iter=30)
    joints, w, g, lengths = slv.unpack(x, truth.n_frames)
    assert proportion_errors_pp(lengths, truth.class_lengths_m)["max_abs"] < 0.3
    assert rotation_error_deg(np.degrees(w), truth.rotvec_deg) < 0.1
    assert np.max(np.abs(np.exp(g) / truth.focal_mm - 1)) < 0.01
    assert rep.cost < slv.residuals(prob, x0, False)


def test_flat_cost_curve_is_not_determined():
    grid = calibration.GRID_MM
    lg = np.log(grid)
    bowl = 1000 + 400 * (lg - np.log(50.0)) ** 2
    f, ok = calibration.pick_minimum(grid, bowl)
    assert ok and f == pytest.approx(50.0, rel=0.05)
    f, ok = calibration.pick_minimum(grid, 1000 + 2 * (lg - np.log(50.0)) ** 2)   # flat
    assert not ok
    f, ok = calibration.pick_minimum(grid, 1000 - 50 * lg)                        # minimum at the edge
    assert not ok


def test_distant_telephoto_clip_reports_focal_not_determined():
    tracks, _ = _clip(60, 1.0, focal_mm=300.0)
    est = estimate_joint(tracks)
    assert est.diagnostics["focal_determined"] is False
    assert any("focal" in w for w in est.diagnostics["warnings"])


def test_missing_joints_still_give_a_full_result():
    tracks, truth = _clip(90, 1.0, dropout=0.2, occlusion_s=1.0)
    assert tracks.missing_fraction() > 0.15
    est = estimate(tracks, "joint", focal_mm=50.0)
    assert est.method == "joint" and len(est.frames) == truth.n_frames
    j3 = np.array([f.joints_3d for f in est.frames])
    assert j3.shape == (truth.n_frames, N_JOINTS, 3) and np.all(np.isfinite(j3))
    assert sum(est.proportions.values()) == pytest.approx(1.0)
    assert all(f.stance in ("l", "r", None) for f in est.frames)
    assert all(np.isfinite(f.focal_mm) and f.focal_mm > 0 for f in est.frames)
    m = np.array(est.diagnostics["world_from_cam0"])
    assert m.shape == (4, 4) and np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-6)
    assert proportion_errors_pp(est.proportions_vector(), truth.proportions)["mean_abs"] < 2.0
    # its camera_moving flags are the paper's spells, and it says so with the spell list itself
    spells = est.diagnostics["spells"]
    flags = np.zeros(truth.n_frames, dtype=bool)
    for sp in spells:
        if sp["kind"] != "still":
            flags[sp["start"]:sp["end"] + 1] = True
    assert np.array_equal(flags, [f.camera_moving for f in est.frames])


def test_frames_with_every_joint_missing_give_poses_and_no_reprojection_error():
    """A cut or the person out of shot for a moment: those frames still get a pose (from their
    neighbours), their reprojection error is None (nothing was seen, not 0 px), and numpy warns of
    nothing on the way (a console full of "Mean of empty slice" in Blender reads as a failure)."""
    import dataclasses
    import warnings

    tracks, truth = _clip(90, 1.0)
    xy = tracks.xy.copy()
    xy[40:50] = np.nan
    tracks = dataclasses.replace(tracks, xy=xy)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        est = estimate(tracks, "joint", focal_mm=50.0)
    j3 = np.array([f.joints_3d for f in est.frames])
    assert len(est.frames) == truth.n_frames and np.all(np.isfinite(j3))
    assert all(est.frames[i].reprojection_px is None for i in range(40, 50))
    seen = [f.reprojection_px for i, f in enumerate(est.frames) if not 40 <= i < 50]
    assert all(r is not None and 0.0 <= r < 5.0 for r in seen)


def test_bad_input_and_cancel():
    tracks, _ = _clip(30, 1.0)
    with pytest.raises(InputError):
        estimate_joint(Tracks(tracks.xy[:5], tracks.conf[:5], tracks.fps, tracks.image_size))
    xy = tracks.xy.copy()
    xy[:, 7] = np.nan
    with pytest.raises(InputError, match="ankle"):
        estimate_joint(Tracks(xy, np.where(np.isfinite(xy[..., 0]), 1.0, 0.0), tracks.fps, tracks.image_size))
    with pytest.raises(Cancelled):
        estimate_joint(tracks, focal_mm=50.0, should_cancel=lambda: True)


def test_progress_moves_through_the_solve_and_never_goes_back():
    from core.estimate import estimate
    from core.synthetic.motion import load_motion
    from core.synthetic.synth import synthesize

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=60), seed=0)
    seen = []
    estimate(tracks, "joint", progress=lambda fraction, message: seen.append((fraction, message)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and 0.0 <= fractions[0] and fractions[-1] <= 1.0
    # the long part reports each iteration, so the bar does not sit still for seconds
    assert sum("iteration" in m for _, m in seen) >= 3


def test_a_detectors_few_stretched_frames_do_not_lengthen_the_start_on_its_tracks():
    """The paper's lengths are each segment's largest per-frame lower bound: twelve frames whose ankle a
    detector put 40 % further along the shank (out of 300) make that shank long.  On tracks marked as
    a detector's (``meta["detector_errors"]``, set by ``core.estimate.estimate``) the joint method's
    start takes a high quantile of the bounds instead and stays near the truth."""
    from core.joint_solve.pipeline import paper_initialisation
    from core.skeleton import CLASSES, JOINT_INDEX

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=300), noise_px=1.0, seed=3)
    xy = tracks.xy.copy()
    frames = np.arange(100, 112)
    knee, ankle = JOINT_INDEX["l_knee"], JOINT_INDEX["l_ankle"]
    xy[frames, ankle] += 0.4 * (xy[frames, ankle] - xy[frames, knee])
    stretched = tracks.replaced(xy=xy)
    shank = CLASSES.index("shank")
    plain = paper_initialisation(stretched, None, 1.75)["proportions"]
    wary = paper_initialisation(stretched.replaced(meta={**stretched.meta, "detector_errors": True}), None,
                                1.75)["proportions"]
    assert 100 * (plain[shank] - truth.proportions[shank]) > 1.0
    assert abs(100 * (wary[shank] - truth.proportions[shank])) < 0.6
