"""The estimate's self-checks: silent on a clean clip, specific when the answer should not be trusted."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from core.estimate import estimate
from core.self_check import check_estimate
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


@pytest.fixture(scope="module")
def still_walk():
    tracks, truth = synthesize(load_motion("builtin:walk", fps=30.0), kinds="still", noise_px=1.0, seed=0)
    return tracks, truth, estimate(tracks, "joint", focal_mm=50.0)


def test_a_clean_clip_carries_no_flag(still_walk):
    tracks, _, est = still_walk
    check = est.diagnostics["self_check"]
    assert check["flags"] == [] and est.diagnostics["trusted"] is True
    assert not [w for w in est.diagnostics["warnings"] if w.startswith("floor:")]
    assert check["metrics"]["residual_median_px"] < 2.0
    assert all(f.reprojection_px is not None for f in est.frames)


def test_a_camera_that_does_not_explain_the_tracks_is_flagged(still_walk):
    tracks, _, est = still_walk
    bad = copy.deepcopy(est)
    for i, f in enumerate(bad.frames):
        f.rotvec_deg = (0.0, 3.0 * np.sin(i / 10.0), 0.0)      # a pan the footage does not show
    codes = {f["code"] for f in check_estimate(bad, tracks)["flags"]}
    assert "fit" in codes


def test_implausible_proportions_are_flagged(still_walk):
    tracks, _, est = still_walk
    bad = copy.deepcopy(est)
    bad.proportions = dict(bad.proportions)
    bad.proportions["lower_spine"] *= 5.0
    assert "proportions" in {f["code"] for f in check_estimate(bad, tracks)["flags"]}


def test_frames_with_a_limb_mirrored_in_depth_are_marked_and_flagged(still_walk):
    """Both shanks mirrored in depth (each shank vector's depth negated in the frame's camera axes): the
    frames where that bends a knee visibly are marked (about a third of the walk's), and the clip says so in
    one warning; the clean estimate has hardly a frame marked and no such flag."""
    from core.motion_prior.evaluation import with_bones_mirrored
    from core.skeleton import JOINT_INDEX

    tracks, _, est = still_walk
    clean = est.diagnostics["self_check"]
    assert "pose" not in {f["code"] for f in clean["flags"]}
    assert len(clean["implausible_frames"]) < 0.05 * len(est.frames)
    shanks = [JOINT_INDEX[n] - 1 for n in ("l_ankle", "r_ankle")]
    bad = with_bones_mirrored(est, shanks)
    check = check_estimate(bad, tracks)
    assert len(check["implausible_frames"]) > 0.25 * len(bad.frames)
    assert [f["code"] for f in check["flags"]].count("pose") == 1


def test_heavy_input_damage_is_flagged(still_walk):
    tracks, _, est = still_walk
    cleaning = {"rejected_share": 0.08, "swapped_share": 0.3}
    codes = {f["code"] for f in check_estimate(copy.deepcopy(est), tracks, cleaning)["flags"]}
    assert {"input_outliers", "input_swaps"} <= codes


def test_joints_a_detector_only_guessed_are_named(still_walk):
    tracks, _, est = still_walk
    check = check_estimate(copy.deepcopy(est), tracks)
    assert "input_unsure" not in {f["code"] for f in check["flags"]} and check["metrics"]["unsure_joints"] == {}
    from core.skeleton import JOINT_INDEX

    conf = tracks.conf.copy()
    conf[:, JOINT_INDEX["l_ankle"]] = 0.12            # as BlazePose reports a foot out of the picture
    conf[:, JOINT_INDEX["l_knee"]] = np.where(np.arange(tracks.n_frames) % 3, 0.2, 0.9)
    guessed = tracks.replaced(conf=conf)
    flags = [f for f in check_estimate(copy.deepcopy(est), guessed)["flags"] if f["code"] == "input_unsure"]
    assert len(flags) == 1 and "l_knee 0.20" in flags[0]["message"] and "l_ankle 0.12" in flags[0]["message"]
    assert "r_ankle" not in flags[0]["message"]


def test_a_detectors_usual_confidence_raises_no_doubt():
    """The generator's detector model (confidence falling with the error, outliers 0.05-0.6) is not 'unsure'."""
    from core.synthetic.footage_sim.detector import TYPICAL

    tracks, _ = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=200), noise_px=1.0, seed=3,
                           detector=TYPICAL)
    est = estimate(tracks, "paper")
    assert "input_unsure" not in {f["code"] for f in est.diagnostics["self_check"]["flags"]}


def test_tracks_that_jump_to_another_person_are_flagged(still_walk):
    tracks, _, est = still_walk
    xy = tracks.xy.copy()
    xy[150:] += np.array([200.0, 0.0])                         # someone else, further right, from frame 150 on
    jumped = tracks.replaced(xy=xy)
    flags = [f for f in check_estimate(copy.deepcopy(est), tracks, raw=jumped)["flags"] if f["code"] == "input_people"]
    assert len(flags) == 1 and "at frame 150" in flags[0]["message"]
    assert "--frames 0-149" in flags[0]["message"] or f"--frames 150-{tracks.n_frames - 1}" in flags[0]["message"]
    assert "input_people" not in {f["code"] for f in check_estimate(copy.deepcopy(est), tracks)["flags"]}


def test_joints_missing_on_both_sides_are_named(still_walk):
    from core.skeleton import JOINT_INDEX

    tracks, _, est = still_walk
    n = tracks.n_frames
    xy = tracks.xy.copy()
    xy[: n // 2, JOINT_INDEX["l_wrist"]] = np.nan          # half the clip without the left wrist: the right one
    def sparse(xy):
        return [f for f in check_estimate(copy.deepcopy(est), tracks.replaced(xy=xy))["flags"]
                if f["code"] == "input_sparse"]
    assert sparse(xy) == []
    xy[n // 3:, JOINT_INDEX["r_wrist"]] = np.nan           # ... and two thirds without the right one
    flags = sparse(xy)
    assert len(flags) == 1 and "r_wrist 67 %" in flags[0]["message"] and "l_wrist 50 %" in flags[0]["message"]


def test_a_missing_joint_held_by_two_present_neighbours_is_not_sparse(still_walk):
    from core.skeleton import JOINT_INDEX

    tracks, _, est = still_walk
    n = tracks.n_frames
    xy = tracks.xy.copy()
    xy[: 2 * n // 3, JOINT_INDEX["thorax"]] = np.nan       # under the spine, neck and shoulders, all present
    def sparse(xy):
        return [f for f in check_estimate(copy.deepcopy(est), tracks.replaced(xy=xy))["flags"]
                if f["code"] == "input_sparse"]
    assert sparse(xy) == []
    for name in ("neck", "l_shoulder", "r_shoulder"):      # for half the clip only the spine is left by it
        xy[: n // 2, JOINT_INDEX[name]] = np.nan
    flags = sparse(xy)
    assert len(flags) == 1 and "thorax 50 %" in flags[0]["message"]


def test_the_lens_flag_weighs_the_background_with_the_lens_prior(still_walk):
    """A 0.3 degree turn says nothing of the lens (sigma of log f 1.5 from the background alone), but the
    lens is held near the prior's centre, so the angles cannot be off by more than the turn times the
    prior's spread: no flag.  A 4 degree turn with the lens 30 % uncertain is."""
    tracks, _, est = still_walk
    def codes(turn, sigma_data, sigma_prior):
        e = copy.deepcopy(est)
        with_prior = 1.0 / np.sqrt(sigma_data ** -2 + sigma_prior ** -2)
        e.diagnostics["scene_camera"] = {"used": True, "turn_deg": turn, "log_focal_sigma": sigma_data,
                                         "log_focal_sigma_with_prior": with_prior, "focal_reason": "-"}
        e.diagnostics["focal_determined"] = False
        return {f["code"] for f in check_estimate(e, tracks)["flags"]}
    assert "camera_focal" not in codes(0.3, 1.5, 1.0)
    assert "camera_focal" in codes(4.0, 0.3, 1.0)
    assert "camera_focal" not in codes(4.0, 0.3, 0.05)          # a focal length given
