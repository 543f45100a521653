"""A person standing on the spot, filmed by a camera that never stops: the solve keeps the camera the
planted feet show, instead of starting from a camera standing still as it does for a runner, reads a
zoom from the figure's size, and holds the hips smooth and the planted feet still."""

import numpy as np
import pytest

from core.joint_solve import pipeline
from core.joint_solve.camera_init import figure_log_zoom
from core.joint_solve.stance import feet_apart_speed, hips_over_feet_speed
from core.synthetic.footage_sim import HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize

#: An operator who pans, tilts and zooms again and again, never holding still for long.
RESTLESS = HandheldOperator(moves_per_s=2.0, duration_range_s=(0.5, 1.0))


def _film(clip: str):
    return synthesize(load_motion(clip, fps=30.0, max_frames=150), focal_mm=35.0, noise_px=0.5, seed=3,
                      operator=RESTLESS)


@pytest.mark.parametrize("clip, standing", [("builtin:stand", True), ("builtin:walk", False), ("builtin:run", False)])
def test_feet_apart_speed_tells_standing_from_stepping(clip, standing):
    tracks, _ = _film(clip)
    speed = feet_apart_speed(tracks.xy, tracks.fps)
    assert (speed < pipeline.STANDING_FEET_SPEED) == standing
    assert speed < 0.3 if standing else speed > 1.0


@pytest.mark.parametrize("clip, standing", [("builtin:stand", True), ("builtin:walk", False), ("builtin:run", False)])
def test_quick_steps_and_moving_hips_are_read_too(clip, standing):
    tracks, _ = _film(clip)
    p90 = feet_apart_speed(tracks.xy, tracks.fps, quantile=0.9)
    hips = hips_over_feet_speed(tracks.xy, tracks.fps)
    assert (p90 < pipeline.ZOOM_FEET_SPEED_P90) == standing
    assert (hips < pipeline.ZOOM_STILL_HIPS_SPEED) == standing
    assert p90 >= feet_apart_speed(tracks.xy, tracks.fps)


def test_feet_apart_speed_needs_both_ankles_seen():
    tracks, _ = _film("builtin:stand")
    xy = tracks.xy.copy()
    xy[:, 0, :] = np.nan
    assert np.isfinite(feet_apart_speed(xy, tracks.fps))        # any joint may be lost, the ankles are read
    assert np.isnan(feet_apart_speed(np.full((10, 17, 2), np.nan), 30.0))


def test_standing_person_keeps_the_planted_feet_camera_and_a_runner_starts_still():
    tracks, truth = _film("builtin:stand")
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    assert np.mean(~paper["moving"]) < 0.10                     # no still spell: the case the rule is for
    yaw = np.degrees(np.ptp(paper["rotvec"][:, 1]))
    true_yaw = np.ptp(np.asarray(truth.rotvec_deg)[:, 1])
    assert yaw > 0.5 * true_yaw > 2.0
    assert not any("solve starts from a camera standing still" in w for w in paper["warnings"])

    tracks, _ = _film("builtin:run")
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    assert np.all(paper["rotvec"] == 0.0)
    assert any("solve starts from a camera standing still" in w for w in paper["warnings"])


def test_figure_log_zoom_follows_the_zoom_of_a_camera_on_a_standing_person():
    tracks, truth = _film("builtin:stand")
    true = np.log(np.asarray(truth.focal_mm, dtype=float) / float(np.ravel(truth.focal_mm)[0]))
    assert np.ptp(true) > 0.1                                   # the operator zooms by more than 10 %
    found = figure_log_zoom(tracks.xy, tracks.fps, pipeline.ZOOM_FROM_FIGURE_SMOOTH_S, 35.0, tracks.image_size)
    assert found[0] == 0.0
    assert np.median(np.abs(found - true)) < 0.02
    assert np.corrcoef(found, true)[0, 1] > 0.95


def test_figure_log_zoom_is_flat_for_a_still_camera_and_survives_lost_joints():
    motion = load_motion("builtin:stand", fps=30.0, max_frames=150)
    tracks, _ = synthesize(motion, focal_mm=35.0, noise_px=1.0, seed=4, kinds=())
    xy = tracks.xy.copy()
    xy[40:60] = np.nan                                          # the person lost for 20 frames
    found = figure_log_zoom(xy, tracks.fps, 0.3, 35.0, tracks.image_size)
    assert np.all(np.isfinite(found)) and np.abs(found).max() < 0.02


def test_standing_person_starts_from_the_figures_zoom():
    # a take whose zooms the paper's method misses (it holds the focal length: 18 % off on most frames)
    tracks, truth = synthesize(load_motion("builtin:stand", fps=30.0, max_frames=150), focal_mm=35.0, noise_px=0.5,
                               seed=7, operator=RESTLESS)
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    true = np.asarray(truth.focal_mm, dtype=float) / float(np.ravel(truth.focal_mm)[0])
    off = np.abs(np.log(paper["focal_ratio"] / true))
    assert np.median(off) < 0.03 and np.percentile(off, 90) < 0.08


def test_standing_person_on_a_still_camera_keeps_a_still_zoom():
    motion = load_motion("builtin:stand", fps=30.0, max_frames=150)
    tracks, _ = synthesize(motion, focal_mm=35.0, noise_px=1.0, seed=4, kinds=())
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    assert np.mean(~paper["moving"]) >= pipeline.ZOOM_STILL_SHARE_BELOW
    assert np.all(paper["focal_ratio"] == 1.0)


@pytest.mark.parametrize("clip, standing", [("builtin:stand", True), ("builtin:walk", False), ("builtin:run", False)])
def test_standing_on_the_spot_reads_the_standing_figure_alone(clip, standing):
    tracks, _ = _film(clip)
    assert pipeline.standing_on_the_spot(tracks) == standing
    term = pipeline._standing_term(pipeline.standing_on_the_spot(tracks))
    assert (term is not None) == standing
    if standing:
        assert term == {"accel_ms2": pipeline.STANDING_HIPS_ACCEL_MS2, "feet": None}


def test_standing_persons_planted_feet_hold_still_under_a_detectors_errors(monkeypatch):
    # a handheld operator and a detector's errors make a standing person's legs jitter; the solve holds the
    # hips smooth and each foot where it stands, so the planted ankles stop sliding and the jitter drops
    from core.estimate import estimate
    from core.evaluation import metrics
    from core.synthetic.footage_sim.detector import TYPICAL

    motion = load_motion("builtin:stand", fps=30.0, max_frames=150)
    tracks, truth = synthesize(motion, focal_mm=50.0, noise_px=1.0, seed=3, view_offset_deg=-42.0,
                               operator=HandheldOperator(), detector=TYPICAL)
    planted = metrics.planted_from_stance(truth.stance, truth.n_frames)
    found = {}
    for accel in (pipeline.STANDING_HIPS_ACCEL_MS2, None):
        monkeypatch.setattr(pipeline, "STANDING_HIPS_ACCEL_MS2", accel)
        est = estimate(tracks, "joint")
        assert est.diagnostics["standing_on_the_spot"] is True
        joints = np.array([f.joints_3d for f in est.frames])
        found[accel] = (metrics.planted_foot_speed_mm_s(joints, truth.joints_3d, truth.fps, planted)["excess_mm_s"],
                        metrics.acceleration_error_mm_s2(joints, truth.joints_3d, truth.fps, "clip"),
                        metrics.mpjpe_per_frame_m(joints, truth.joints_3d))
    (held, jitter, err), (loose, loose_jitter, loose_err) = found.values()
    assert loose > 100.0 and held < 0.3 * loose
    assert jitter < 0.85 * loose_jitter
    assert err < loose_err + 0.003


def test_each_window_of_a_long_standing_clip_holds_its_own_planted_feet(monkeypatch):
    # a clip solved in windows finds each window's planted feet on that window's first solve
    monkeypatch.setattr(pipeline, "SINGLE_MAX", 100)
    monkeypatch.setattr(pipeline, "WINDOW", 80)
    monkeypatch.setattr(pipeline, "OVERLAP", 20)
    seen = []
    real = pipeline.signs_again

    def spy(prob, x, rep, **kw):
        seen.append(prob.standing)
        return real(prob, x, rep, **kw)

    monkeypatch.setattr(pipeline, "signs_again", spy)
    tracks, _ = _film("builtin:stand")
    est = pipeline.estimate_joint(tracks)
    assert len(seen) >= 2
    for standing in seen:
        assert standing["accel_ms2"] == pipeline.STANDING_HIPS_ACCEL_MS2
        feet = standing["feet"]
        assert feet.dtype == bool and feet.shape[1] == 2 and feet.mean() > 0.5
    assert est.diagnostics["standing_on_the_spot"] is True


def test_a_zoom_the_paper_takes_for_a_still_camera_is_read_from_the_figure(monkeypatch):
    # a zoom about the picture's centre with no pan or tilt: the planted feet stay put in the picture, so
    # the paper's method sees a still camera throughout; the figure's size still shows the zoom
    tracks, truth = synthesize(load_motion("builtin:stand", fps=30.0, max_frames=240), focal_mm=35.0,
                               noise_px=1.0, seed=0, kinds=("zoom",))
    true = np.asarray(truth.focal_mm, dtype=float) / float(np.ravel(truth.focal_mm)[0])
    assert np.ptp(np.log(true)) > 0.3
    with monkeypatch.context() as m:
        m.setattr(pipeline, "ZOOM_FIGURE_RANGE", np.inf)             # the paper's camera alone
        held = pipeline.paper_initialisation(tracks, None, 1.75)
    assert np.mean(~held["moving"]) >= pipeline.ZOOM_STILL_SHARE_BELOW
    assert np.all(held["focal_ratio"] == 1.0)
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    off = np.abs(np.log(paper["focal_ratio"] / true))
    assert np.median(off) < 0.03 and np.percentile(off, 90) < 0.08
