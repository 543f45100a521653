"""The planted ankle's creep: measured in the still spells, taken out of a rotating camera's track."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core.evaluation.metrics import rotation_error_deg
from core.peng_li.foot_drift import MIN_PAIRS, stance_ankle_drift, without_drift
from core.peng_li.params import DRIFT_CORRECTED, PAPER
from core.peng_li.pipeline import estimate_paper
from core.skeleton import FEET
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def test_drift_is_the_planted_foots_mean_step_in_still_frames():
    n = 40
    feet = np.zeros((n, 2, 2))
    stance = np.where(np.arange(n) < 20, 0, 1)
    feet[:, 0] = np.arange(n)[:, None] * [0.02, -0.01]         # left creeps while planted ...
    feet[20:, 0] += np.arange(20)[:, None] * [1.0, 0.5]          # ... then swings away fast
    feet[:20, 1] = np.arange(20)[:, None] * [-0.8, 0.3]          # right swings, then creeps
    feet[20:, 1] = feet[19, 1] + np.arange(1, 21)[:, None] * [0.02, -0.01]
    still = np.ones(n, dtype=bool)
    still[30:] = False                                           # a moving camera does not count
    feet[30:] += np.arange(10)[:, None, None] * 5.0
    np.testing.assert_allclose(stance_ankle_drift(feet, still, stance), [0.02, -0.01], atol=1e-12)


def test_swaps_missing_feet_and_too_few_frames_give_no_or_clean_drift():
    n = MIN_PAIRS + 1
    feet = np.cumsum(np.ones((n, 2, 2)), axis=0)                 # both feet step 1 per frame
    stance = np.zeros(n, dtype=int)
    still = np.ones(n, dtype=bool)
    np.testing.assert_allclose(stance_ankle_drift(feet, still, stance), [1.0, 1.0])
    feet_gap = feet.copy()
    feet_gap[3, 0] = np.nan                                      # two pairs lost: below the minimum
    assert not stance_ankle_drift(feet_gap, still, stance).any()
    alternating = np.arange(n) % 2                               # every pair a swap: nothing to measure
    assert not stance_ankle_drift(feet, still, alternating).any()
    assert not stance_ankle_drift(feet[:1], still[:1], stance[:1]).any()


def test_without_drift_removes_the_step_from_both_feet():
    feet = np.random.default_rng(0).normal(size=(12, 2, 2))
    out = without_drift(feet, np.array([0.5, -0.25]))
    np.testing.assert_allclose(np.diff(out, axis=0), np.diff(feet, axis=0) - [0.5, -0.25])
    np.testing.assert_allclose(out[0], feet[0])


@pytest.fixture(scope="module")
def creeping_walk():
    """The built-in walk at 1 px with every planted ankle creeping (0.3, -0.2) px per frame, as a
    real ankle does over heel, flat foot and heel-off; a swinging foot keeps its offset (no jump)."""
    tracks, truth = synthesize(load_motion("builtin:walk", fps=30.0), noise_px=1.0, seed=0)
    xy = tracks.xy.copy()
    offset = {"l": np.zeros(2), "r": np.zeros(2)}
    for i, s in enumerate(truth.stance):
        if s is not None:
            offset[s] = offset[s] + [0.3, -0.2]
        for side in "lr":
            xy[i, FEET[side]] += offset[side]
    return dataclasses.replace(tracks, xy=xy), truth


def test_correction_measures_the_creep_and_keeps_the_camera(creeping_walk):
    tracks, truth = creeping_walk
    paper = estimate_paper(tracks, params=PAPER)
    fixed = estimate_paper(tracks, params=DRIFT_CORRECTED)
    assert paper.diagnostics["stance_drift_px_per_frame"] == [0.0, 0.0]     # the paper's setting: off
    np.testing.assert_allclose(fixed.diagnostics["stance_drift_px_per_frame"], [0.3, -0.2], atol=0.1)
    err_paper = rotation_error_deg(np.array([f.rotvec_deg for f in paper.frames]), truth.rotvec_deg)
    err_fixed = rotation_error_deg(np.array([f.rotvec_deg for f in fixed.frames]), truth.rotvec_deg)
    assert err_fixed < 0.5 * err_paper and err_fixed < 0.4
