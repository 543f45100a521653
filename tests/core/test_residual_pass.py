"""The second pass after a solve (core.track_cleaning.residual): points the solved figure and camera
cannot explain are found, and the estimate is solved again without them only when the cleaning saw a
detector's gross errors."""

from __future__ import annotations

import numpy as np

from core.estimate import estimate
from core.synthetic.footage_sim.detector import TYPICAL
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import truth_as_estimate
from core.track_cleaning.residual import residual_outliers


def _walk(**kw):
    return synthesize(load_motion("builtin:walk", max_frames=150), seed=3, **kw)


def test_points_the_true_answer_cannot_explain_are_exactly_the_moved_ones():
    tracks, truth = _walk(noise_px=1.0)
    rng = np.random.default_rng(0)
    xy = tracks.xy.copy()
    picks = {(int(f), int(j)) for f, j in zip(rng.integers(0, tracks.n_frames, 40), rng.integers(0, 17, 40))}
    picks = {(f, j) for f, j in picks if tracks.present[f, j]}
    for f, j in picks:          # 0.6 body scale off: near the body, where a 2D cleaning may let it pass
        xy[f, j] += rng.choice([-1, 1], 2) * 25.0
    moved = tracks.replaced(xy=xy)
    found = residual_outliers(moved, truth_as_estimate(truth))
    expected = np.zeros_like(found)
    for f, j in picks:
        expected[f, j] = True
    assert found[expected].all() and not found[~expected].any()
    assert not residual_outliers(tracks, truth_as_estimate(truth)).any()


def test_second_pass_runs_on_a_detectors_tracks_and_says_what_it_dropped():
    tracks, _ = _walk(noise_px=1.0, detector=TYPICAL)
    heard = []
    est = estimate(tracks, "joint", progress=lambda fraction, message="": heard.append(fraction))
    assert heard == sorted(heard) and heard[-1] > 0.9 and any(0.5 < h < 0.9 for h in heard)   # one bar, two solves
    dropped = est.diagnostics["cleaning"]["unexplained"]
    assert dropped > 0
    per_frame = sum(len(f.rejected or []) for f in est.frames)
    assert per_frame >= dropped + est.diagnostics["cleaning"]["outliers"]
    once = estimate(tracks, "joint", residual=None)
    assert once.diagnostics["cleaning"]["unexplained"] == 0


def test_clean_tracks_get_no_second_pass():
    tracks, _ = _walk(noise_px=1.0)
    est = estimate(tracks, "joint")
    assert est.diagnostics["cleaning"]["unexplained"] == 0
    paper = estimate(tracks, "paper")
    assert paper.diagnostics["cleaning"]["unexplained"] == 0
