"""``bench/ceiling.py`` measures how close the joint objective gets from the truth; its claims in the README
rest on its truth start really being the truth, and on the truth-started solve using the shipped objective."""


import numpy as np
import pytest

from core.evaluation.evaluate import score
from core.joint_solve.stance import stance_codes
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


@pytest.fixture(scope="module")
def ceiling(load_bench):
    return load_bench("ceiling.py")


@pytest.fixture(scope="module")
def clip():
    # the built-in walk (seed 0): a still spell, a tilt, a still spell in 120 frames
    return synthesize(load_motion("builtin:walk", max_frames=120, fps=30.0), noise_px=1.0, seed=0)


def test_the_truth_row_scores_zero_everywhere(ceiling, clip):
    tracks, truth = clip
    sc = score(ceiling.oracle(tracks, truth, 0), truth)
    assert sc["proportions"]["max_abs"] < 1e-6
    assert sc["rotation_error_deg"] < 1e-6
    assert sc["mpjpe_frame_mm"] < 1e-3 and sc["mpjpe_clip_mm"] < 1e-3
    assert sc["zoom_focal_error_pct"] is None or np.isnan(sc["zoom_focal_error_pct"]) \
        or sc["zoom_focal_error_pct"] < 1e-6
    assert sc["stance_accuracy"] == 1.0


def test_the_truth_state_holds_the_true_floor(ceiling, clip):
    from core.joint_solve import solver as slv
    from core.joint_solve.ground import planted_points

    tracks, truth = clip
    st = stance_codes(truth.stance)
    x = ceiling.truth_state(truth, st)
    up, offset = slv.unpack_ground(x, tracks.n_frames)
    heights = planted_points(truth.joints_3d, st) @ up - offset
    assert np.linalg.norm(up) == pytest.approx(1.0)
    # up points from the feet to the head (the solver's upright and level terms assume it)
    torso = truth.joints_3d[:, 2] - truth.joints_3d[:, 0]                     # pelvis -> thorax
    assert np.min(torso @ up / np.linalg.norm(torso, axis=1)) > 0.9
    # planted ankles of the procedural walk stay on the floor: within a few millimetres of one plane
    assert np.max(np.abs(heights)) < 0.005


def test_solves_from_the_truth_stay_near_it(ceiling, clip):
    tracks, truth = clip
    for est in (ceiling.truth_start(tracks, truth, 5), ceiling.oracle(tracks, truth, 5),
                ceiling.truth_start(tracks, truth, 5, camera_prior=False),
                ceiling.truth_start(tracks, truth, 5, true_stance=True)):
        sc = score(est, truth)
        # measured on this clip: 17-21 mm per frame; the shipped method gives 52
        assert sc["mpjpe_frame_mm"] < 40.0
        assert sc["proportions"]["max_abs"] < 1.0
