"""Input cleaning: far-off points, gross outliers and left/right exchanges, against the generator's log."""

from __future__ import annotations

import numpy as np
import pytest

from core.estimate import estimate
from core.evaluation.metrics import proportion_errors_pp
from core.result import estimate_from_dict, estimate_to_dict
from core.skeleton import JOINT_INDEX
from core.synthetic.footage_sim import DetectorErrors
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.track_cleaning import clean_tracks
from core.tracks import Tracks


@pytest.fixture(scope="module")
def walk():
    return synthesize(load_motion("builtin:walk", fps=30.0), noise_px=1.0, seed=3)


def _film(errors: DetectorErrors, name="builtin:walk", seed=3):
    return synthesize(load_motion(name, fps=30.0), noise_px=1.0, seed=seed, detector=errors)


def test_a_clean_clip_is_left_alone():
    for name in ("builtin:walk", "builtin:run"):
        tracks = synthesize(load_motion(name, fps=30.0), noise_px=1.0, seed=3)[0]
        cleaned, report = clean_tracks(tracks)
        assert report.rejected.sum() <= 0.001 * tracks.present.sum()
        assert report.swapped_frames().sum() == 0


def test_a_joint_far_off_the_picture_is_missing_not_a_74_percent_neck(walk):
    tracks, truth = walk
    xy = tracks.xy.copy()
    xy[40, JOINT_INDEX["head"]] = (1e300, 1e300)
    bad = Tracks(xy, tracks.conf, tracks.fps, tracks.image_size)
    cleaned, report = clean_tracks(bad)
    assert report.outside[40, JOINT_INDEX["head"]] and report.outside.sum() == 1
    est = estimate(bad, "paper")
    assert proportion_errors_pp(est.proportions_vector(), truth.proportions)["max_abs"] < 3.0
    assert est.frames[40].rejected == ["head"]


def test_gross_outliers_are_found(walk):
    tracks, truth = _film(DetectorErrors(outliers=0.02))
    cleaned, report = clean_tracks(tracks)
    true = np.zeros(tracks.conf.shape, dtype=bool)
    for f, j in truth.generator["detector_log"]["outliers"]:
        true[f, j] = True
    found = report.outliers
    assert (found & true).sum() >= 0.85 * true.sum()
    assert (found & ~true).sum() <= 0.002 * tracks.present.sum()


def test_left_right_exchanges_are_undone(walk):
    tracks, truth = _film(DetectorErrors(swaps=0.08))
    cleaned, report = clean_tracks(tracks)
    true = np.zeros(tracks.n_frames, dtype=bool)
    for e in truth.generator["detector_log"]["swaps"]:
        true[e["start"]:e["end"] + 1] = True
    found = report.swapped_frames()
    assert (found & true).sum() >= 0.6 * true.sum()
    assert (found & ~true).sum() <= 0.02 * tracks.n_frames
    # after undoing, the ankles sit where the clean film has them on far more frames than before
    clean = synthesize(load_motion("builtin:walk", fps=30.0), noise_px=1.0, seed=3)[0]
    ank = [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
    before = np.nansum(np.linalg.norm(tracks.xy[:, ank] - clean.xy[:, ank], axis=-1) > 5)
    after = np.nansum(np.linalg.norm(cleaned.xy[:, ank] - clean.xy[:, ank], axis=-1) > 5)
    assert after < 0.5 * before


def test_cleaning_rescues_the_proportions_and_says_what_it_did():
    tracks, truth = _film(DetectorErrors(outliers=0.01, swaps=0.05, extremity_jitter=True))
    raw = estimate(tracks, "paper", cleaning=None)
    cleaned = estimate(tracks, "paper")
    e_raw = proportion_errors_pp(raw.proportions_vector(), truth.proportions)["mean_abs"]
    e_clean = proportion_errors_pp(cleaned.proportions_vector(), truth.proportions)["mean_abs"]
    assert e_clean < 1.0 and e_clean < 0.5 * e_raw
    summary = cleaned.diagnostics["cleaning"]
    assert summary["outliers"] > 0 and summary["swapped_frames"] > 0
    assert any(f.rejected for f in cleaned.frames) and any(f.swapped for f in cleaned.frames)
    back = estimate_from_dict(estimate_to_dict(cleaned))
    assert [f.rejected for f in back.frames] == [f.rejected for f in cleaned.frames]
    assert [f.swapped for f in back.frames] == [f.swapped for f in cleaned.frames]


def _two_people(walk_tracks, at):
    """The walk's tracks up to frame ``at``, then a second, smaller person further right (a detector that
    slid onto someone else)."""
    xy = walk_tracks.xy.copy()
    centre = np.nanmean(xy[at:], axis=1, keepdims=True)
    xy[at:] = centre + 0.8 * (xy[at:] - centre) + np.array([180.0, -20.0])
    return walk_tracks.replaced(xy=xy)


def test_a_jump_to_another_person_is_found_and_a_detectors_errors_are_not():
    from core.synthetic.footage_sim.detector import TYPICAL
    from core.track_cleaning.people import person_switches

    for seed in (1, 2, 3):
        damaged, _ = _film(TYPICAL, seed=seed)                 # outliers, left/right swaps (whole body too), gaps
        assert person_switches(damaged.xy).size == 0, seed
        run, _ = _film(TYPICAL, name="builtin:run", seed=seed)
        assert person_switches(run.xy).size == 0, seed
    tracks, _ = _film(DetectorErrors())
    assert person_switches(_two_people(tracks, 120).xy).tolist() == [120]
    glitch = tracks.xy.copy()
    glitch[60:63] += np.array([150.0, 40.0])                   # the whole figure thrown off for three frames
    assert person_switches(glitch).size == 0


def test_the_longest_one_person_stretch_starts_at_a_switch_and_stops_at_a_loss():
    from core.track_cleaning.people import longest_one_person_stretch

    found = np.ones(300, dtype=bool)
    assert longest_one_person_stretch([], found) == (0, 300)
    assert longest_one_person_stretch([120], found) == (120, 300)           # the switch frame is the new person's
    assert longest_one_person_stretch([200], found) == (0, 200)
    found[150:160] = False                                                  # lost for ten frames
    assert longest_one_person_stretch([120], found) == (160, 300)
    assert longest_one_person_stretch([], np.zeros(5, dtype=bool)) == (0, 0)
