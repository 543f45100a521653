"""Fusing a detector's joint positions with a tracker's runs (core/track_refinement)."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import InputError
from core.skeleton import JOINT_INDEX
from core.track_refinement import FuseSettings, TrackedRun, fuse_joint, refine_tracks, seed_plan
from core.tracks import Tracks

N = 150


def _path(n=N):
    t = np.arange(n, dtype=float)
    return np.stack([300 + 2.0 * t + 15 * np.sin(t / 2.0), 200 + 30 * np.sin(t / 6.0)], axis=1)


def _runs(truth, detector, window=5, step_px=0.15, seed=0):
    """Runs as Blender's runner makes them: seeded at the detector, or where the previous run reached
    when the detector is missing or far from there; following the true motion with a small random walk."""
    rng = np.random.default_rng(seed)
    runs = []
    for s in range(0, len(truth) - 1, window):
        e = min(len(truth), s + window + 1)
        start = detector[s]
        if runs and not (np.isfinite(start).all() and np.linalg.norm(start - runs[-1].xy[-1]) < 8.0):
            start = runs[-1].xy[-1]
        walk = np.cumsum(rng.normal(0.0, step_px, (e - s, 2)), axis=0)
        runs.append(TrackedRun(s, start + truth[s:e] - truth[s] + walk - walk[0]))
    return runs


def _detector(truth, sigma=2.0, seed=1):
    return truth + np.random.default_rng(seed).normal(0.0, sigma, truth.shape)


def _rms(a, b, mask=None):
    d = np.sum((a - b) ** 2, axis=1)
    return float(np.sqrt(np.mean(d if mask is None else d[mask])))


def test_fused_path_beats_the_detector_and_learns_its_noise():
    truth = _path()
    det = _detector(truth)
    fused = fuse_joint(det, _runs(truth, det))
    assert _rms(fused.xy, truth) < 0.35 * _rms(det, truth)
    assert fused.detector_px == pytest.approx(2.0, rel=0.25)
    assert fused.agree.mean() > 0.97 and fused.runs_dropped == 0


def test_misses_of_one_to_three_frames_are_outvoted_and_gaps_bridged():
    truth = _path()
    det = _detector(truth)
    misses = [40, 90, 91, 120, 121, 122]
    det[misses] += (30.0, -22.0)
    det[60:63] = np.nan
    fused = fuse_joint(det, _runs(truth, det))
    assert np.linalg.norm(fused.xy[misses] - truth[misses], axis=1).max() < 3.0
    assert not fused.agree[misses].any()
    assert np.linalg.norm(fused.xy[60:63] - truth[60:63], axis=1).max() < 3.0


def test_a_run_on_the_wrong_thing_is_dropped_and_a_slipped_tail_cut():
    truth = _path()
    det = _detector(truth)
    runs = _runs(truth, det)
    # seeded on a miss: the tracker follows a static background point for the whole run
    runs[10] = TrackedRun(runs[10].start, np.repeat(runs[10].xy[:1], len(runs[10].xy), axis=0))
    # slipped after four frames onto a neighbour that moves differently
    run = runs[20]
    slipped = run.xy.copy()
    slipped[4:] = slipped[4] + np.cumsum(np.full((len(slipped) - 4, 2), 6.0), axis=0)
    runs[20] = TrackedRun(run.start, slipped)
    fused = fuse_joint(det, runs)
    assert fused.runs_dropped == 1
    frames = np.r_[runs[10].frames(), runs[20].frames()]
    # what is left there is no worse than the detector (a kept static run would pull four frames flat)
    assert _rms(fused.xy[frames], truth[frames]) <= _rms(det[frames], truth[frames])
    assert np.linalg.norm(fused.xy[frames] - truth[frames], axis=1).max() < 8.0


def test_without_runs_the_detector_is_returned():
    truth = _path(30)
    det = _detector(truth)
    det[5] = np.nan
    fused = fuse_joint(det, [])
    np.testing.assert_array_equal(fused.xy, det)
    assert fused.runs_used == 0 and not fused.agree[5]


def test_frames_no_source_reaches_stay_missing():
    truth = _path(40)
    det = _detector(truth)
    det[20:] = np.nan
    runs = [TrackedRun(0, truth[0:11] - truth[0] + det[0]), TrackedRun(25, truth[25:31])]   # the second: no detector
    fused = fuse_joint(det, runs, FuseSettings(min_frames_for_noise=5))
    assert np.isfinite(fused.xy[:20]).all() and np.isnan(fused.xy[20:]).all()


def _tracks(xy):
    conf = np.where(np.isfinite(xy[..., 0]), 1.0, 0.0)
    return Tracks(xy, conf, 30.0, (720.0, 480.0), source="test")


def test_refine_tracks_policies_and_report():
    truth = np.stack([_path() + 10.0 * j for j in range(17)], axis=1)
    rng = np.random.default_rng(4)
    det = truth + rng.normal(0.0, 2.0, truth.shape)
    head = JOINT_INDEX["head"]
    det[50, head] += 40.0
    det[70, head] = np.nan
    tracks = _tracks(det)
    runs = {j: _runs(truth[:, j], det[:, j], seed=j) for j in range(17)}
    runs.pop(JOINT_INDEX["l_wrist"])                     # no run: that joint is left as it was
    kept, report = refine_tracks(tracks, runs)
    assert kept.xy[50, head] == pytest.approx(det[50, head])
    assert kept.conf[70, head] == 0.5 and np.linalg.norm(kept.xy[70, head] - truth[70, head]) < 3.0
    np.testing.assert_array_equal(kept.xy[:, JOINT_INDEX["l_wrist"]], det[:, JOINT_INDEX["l_wrist"]])
    assert report.disagreeing_entries >= 1 and report.filled_entries == 1 and "l_wrist" not in report.joints
    assert kept.meta["refined"]["refined_entries"] == report.refined_entries
    assert "Refined" in report.summary() and "disagreed" in report.summary()
    used, _ = refine_tracks(tracks, runs, disagree="refined")
    assert np.linalg.norm(used.xy[50, head] - truth[50, head]) < 3.0
    gone, _ = refine_tracks(tracks, runs, disagree="missing")
    assert not gone.present[50, head] and np.isnan(gone.xy[50, head]).all()
    others = np.ones(tracks.present.shape, dtype=bool)
    others[:, JOINT_INDEX["l_wrist"]] = False
    assert _rms(kept.xy[others], truth[others]) < 0.5 * _rms(det[others], truth[others], np.isfinite(det[others][:, 0]))
    with pytest.raises(InputError, match="policy"):
        refine_tracks(tracks, runs, disagree="average")


def test_seed_plan():
    xy = np.full((23, 17, 2), 100.0)
    xy[10, :5] = np.nan
    xy[15] = np.nan
    plan = seed_plan(_tracks(xy), 5)
    assert [f for f, _ in plan] == [0, 5, 10, 20]         # frame 15 has no joint to seed
    assert len(plan[2][1]) == 12 and plan[0][1][0] == (100.0, 100.0)
    with pytest.raises(InputError, match="window"):
        seed_plan(_tracks(xy), 0)


def test_carried_seeds_replace_a_missing_or_missed_detector_position():
    from core.track_refinement.refine import carried_seeds

    truth = np.stack([_path(12) + 10.0 * j for j in range(17)], axis=1)
    det = truth + np.random.default_rng(5).normal(0.0, 1.0, truth.shape)
    head, wrist, knee = JOINT_INDEX["head"], JOINT_INDEX["l_wrist"], JOINT_INDEX["l_knee"]
    det[5, head] += 30.0                             # a miss at the seed frame
    det[5, wrist] = np.nan                           # no detection there
    tracks = _tracks(det)
    seeds = {j: tuple(det[5, j]) for j in range(17) if np.isfinite(det[5, j]).all()}
    runs = {j: [TrackedRun(0, truth[0:6, j] + 0.5)] for j in (head, wrist)}
    slipped = truth[0:6, knee].copy()
    slipped[3:] += 20.0                              # slipped before the seed frame: the detector decides
    runs[knee] = [TrackedRun(0, slipped)]
    starts = carried_seeds(tracks, 5, seeds, runs, reseed_px=8.0)
    assert np.linalg.norm(np.subtract(starts[head], truth[5, head])) < 3.0
    assert np.linalg.norm(np.subtract(starts[wrist], truth[5, wrist])) < 3.0
    assert starts[knee] == seeds[knee]
    assert all(starts[j] == seeds[j] for j in seeds if j not in (head, wrist))
