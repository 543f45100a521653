"""When the background followed on the footage can carry the camera (core.background_tracking.verdict): the
generator's scene points can; none, too few in view, or features that move on their own (a crowd) cannot,
and each says so in one line that ends in the fallback."""

from __future__ import annotations

import numpy as np
import pytest

from core.background_tracking import judge_background
from core.background_tracking.verdict import FALLBACK, PREFIX
from core.synthetic.footage_sim import HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.tracks import StaticTracks


@pytest.fixture(scope="module")
def shot():
    filmed, _ = synthesize(load_motion("builtin:walk", max_frames=90), kinds=(), focal_mm=35.0, noise_px=1.0, seed=4,
                           operator=HandheldOperator(moves_per_s=1.5), static_points=16)
    return filmed.replaced(static=None), filmed.static


def _said(text: str) -> bool:
    return text.startswith(PREFIX) and text.endswith(FALLBACK) and "\n" not in text


def test_scene_points_seen_by_a_turning_camera_carry_it(shot):
    joints, static = shot
    assert judge_background(joints, static) == ""
    # a few that move on their own are left out by the scene camera: still enough
    drift = np.zeros_like(static.xy)
    drift[:, :3, 0] = 4.0 * np.arange(joints.n_frames)[:, None]
    assert judge_background(joints, StaticTracks(static.names, static.xy + drift, static.conf)) == ""


def test_no_features_or_too_few_in_view_fall_back(shot):
    joints, static = shot
    none = judge_background(joints, None)
    assert _said(none) and "no background feature" in none
    few = judge_background(joints, static.without(static.names[3:]))
    assert _said(few) and "fewer than 4 background features in view on 90 of 90 frames" in few


def test_a_background_that_moves_on_its_own_falls_back(shot):
    joints, static = shot
    crowd = np.zeros_like(static.xy)
    crowd[:, :12, 0] = 4.0 * np.arange(joints.n_frames)[:, None]       # most of it walks right, 4 px a frame
    text = judge_background(joints, StaticTracks(static.names, static.xy + crowd, static.conf))
    assert _said(text) and "parallax" in text
    rng = np.random.default_rng(0)                                       # every feature wanders its own way
    wander = np.cumsum(rng.normal(0.0, 3.0, static.xy.shape), axis=0)
    assert _said(judge_background(joints, StaticTracks(static.names, static.xy + wander, static.conf)))
