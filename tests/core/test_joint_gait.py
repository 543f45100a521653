"""A walk told from a run by the ankles' picture: a walker filmed by a camera that never stops keeps the camera
the planted feet show, while a runner's solve starts from a camera standing still."""

import numpy as np
import pytest

from core.joint_solve import pipeline
from core.joint_solve.stance import step_period, stride_period
from core.skeleton import FEET
from core.synthetic.footage_sim import HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize

#: An operator who pans, tilts and zooms again and again, never holding still for long.
RESTLESS = HandheldOperator(moves_per_s=2.0, duration_range_s=(0.5, 1.0))
STILL_START = "solve starts from a camera standing still"


def _film(clip: str, frames: int = 180, seed: int = 3):
    return synthesize(load_motion(clip, fps=30.0, max_frames=frames), focal_mm=35.0, noise_px=0.5, seed=seed,
                      operator=RESTLESS)


@pytest.mark.parametrize("clip, stride, walks", [("builtin:walk", (1.0, 1.15), True),
                                                  ("builtin:run", (0.65, 0.8), False)])
def test_the_stride_tells_a_walk_from_a_run_under_a_restless_operator(clip, stride, walks):
    tracks, _ = _film(clip)
    period, corr = stride_period(tracks.xy, tracks.fps)
    assert stride[0] < period < stride[1] and corr > 0.5
    step, _ = step_period(tracks.xy, tracks.fps)
    if walks:      # a run's step may read as its stride (a person seen from the front): only a walk's is sure
        assert pipeline.RUNNING_STEP_S <= step < 0.75
    assert pipeline.walking(tracks) == walks


def test_left_and_right_exchanged_every_other_stride_do_not_make_a_run_a_walk():
    tracks, _ = _film("builtin:run")
    period, _ = stride_period(tracks.xy, tracks.fps)
    xy = tracks.xy.copy()
    n = int(round(period * tracks.fps))
    for start in range(n, len(xy), 2 * n):                  # every other stride, the ankles' labels exchanged
        part = xy[start:start + n]
        part[:, [FEET["l"], FEET["r"]]] = part[:, [FEET["r"], FEET["l"]]]
    swapped = tracks.replaced(xy=xy)
    assert stride_period(xy, tracks.fps)[0] > 1.5 * period     # the stride reads doubled ...
    assert step_period(xy, tracks.fps)[0] == pytest.approx(step_period(tracks.xy, tracks.fps)[0], abs=0.05)
    assert not pipeline.walking(swapped)                       # ... and the step still says a run


def test_no_gait_without_the_ankles_or_a_repeating_picture():
    tracks, _ = _film("builtin:walk")
    xy = tracks.xy.copy()
    xy[: len(xy) * 2 // 3, FEET["l"]] = np.nan                 # the left ankle lost for two thirds of the clip
    assert stride_period(xy, tracks.fps) == (pytest.approx(np.nan, nan_ok=True), 0.0)
    assert np.isnan(step_period(xy[:5], tracks.fps)[0])         # too short for a step
    stand, _ = _film("builtin:stand")
    assert not pipeline.walking(stand)


def test_a_walker_filmed_by_a_restless_operator_keeps_the_planted_feet_camera(monkeypatch):
    # the paper's method finds no still spell (the camera never stops); a walker's feet stand still at every
    # step, so its camera chained from them is the start and the prior, and the planted feet slide less than
    # from a camera standing still, the start kept for runners
    from core.estimate import estimate
    from core.evaluation import metrics

    tracks, truth = _film("builtin:walk")
    paper = pipeline.paper_initialisation(tracks, None, 1.75)
    assert np.mean(~paper["moving"]) < 0.10                      # no still spell: the case the rule is for
    assert np.ptp(paper["rotvec"]) > 0 and not any(STILL_START in w for w in paper["warnings"])

    planted = metrics.planted_from_stance(truth.stance, truth.n_frames) & metrics.planted_from_speed(
        truth.joints_3d, truth.fps, 0.1)
    found = {}
    for stride in (pipeline.WALKING_STRIDE_S, None):
        monkeypatch.setattr(pipeline, "WALKING_STRIDE_S", stride)
        est = estimate(tracks, "joint")
        assert any(STILL_START in w for w in est.diagnostics["warnings"]) == (stride is None)
        joints = np.array([f.joints_3d for f in est.frames])
        found[stride] = (metrics.planted_foot_speed_mm_s(joints, truth.joints_3d, truth.fps, planted)["excess_mm_s"],
                         metrics.mpjpe_clip_m(joints, truth.joints_3d))
    (chained, chained_clip), (still, still_clip) = found.values()
    assert chained < 0.5 * still
    assert chained_clip < still_clip
