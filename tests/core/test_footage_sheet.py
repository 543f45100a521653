"""core.review.footage_sheet: which frames the review page shows, and what is drawn on them."""

from __future__ import annotations

import copy
import re

import numpy as np
import pytest

from core.review.footage_sheet import (
    SKELETON_COLOUR,
    TRACK_COLOUR,
    draw_frame,
    footage_pictures,
    named_frames,
    pick_frames,
    pictures_html,
    thumbnail,
)
from core.review.problems import REJECTED
from core.review.report import review_html
from core.review.residuals import reprojected_pixels
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import truth_as_estimate


@pytest.fixture(scope="module")
def clip():
    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=40), kinds=("pan",), seed=2, noise_px=0.0)
    est = truth_as_estimate(truth)
    for i, fr in enumerate(est.frames):
        fr.reprojection_px = 1.0 + 0.01 * i
    return tracks, est


def test_the_worst_frames_the_named_problems_and_an_even_spread_are_picked(clip):
    _, est = copy.deepcopy(clip)
    est.frames[17].reprojection_px = 9.0
    est.frames[22].rejected = ["l_knee"]
    picks = dict(pick_frames(est, even=4, worst=2))
    assert "worst fit 9.0 px" in picks[17] and "worst fit" in picks[39]
    assert picks[22] == REJECTED
    assert {0, 13, 26, 39} <= set(picks) and "spread" in picks[0]
    assert list(picks) == sorted(picks)
    est.diagnostics["warnings"] = ["input: the tracks jump to another person at frame 30, 31: ... estimate the "
                                   "tracks' frames 0-29 (the longest stretch of one person)"]
    picks = dict(pick_frames(est, even=4, worst=2))
    assert picks[30] == picks[31] == "input warning" and 29 not in picks
    assert named_frames("fit: 40 % of the frames fit poorly (worst frame 12, 3.1 px)") == [12]
    assert len(pick_frames(est, even=40, worst=2, limit=6)) == 6          # the worst and the named kept first
    assert {17, 22} <= {i for i, _ in pick_frames(est, even=40, worst=2, limit=6)}


def test_a_thumbnail_averages_the_pixels_it_covers():
    img = np.zeros((4, 8, 3), np.uint8)
    img[:, ::2] = 200
    small, scale = thumbnail(img, width=4)
    assert small.shape == (2, 4, 3) and scale == 0.5
    assert np.all(small == 100)


def test_the_skeleton_and_the_tracks_are_drawn_where_the_camera_puts_them(clip):
    tracks, est = clip
    w, h = (int(v) for v in tracks.image_size)
    rgb = np.zeros((h, w, 3), np.uint8)
    reproj = reprojected_pixels(est, tracks.image_size)[5]
    img = draw_frame(rgb, tracks.xy[5], tracks.present[5], reproj, width=w // 2)
    assert img.shape == (h // 2, w // 2, 3)
    # the thorax track is a cyan dot; the skeleton passes half-way between the pelvis and the thorax
    tx, ty = np.round(tracks.xy[5, 2] / 2).astype(int)
    assert tuple(img[ty, tx]) == TRACK_COLOUR
    mx, my = np.round((reproj[0] + reproj[1]) / 4).astype(int)
    near = img[my - 1:my + 2, mx - 1:mx + 2].reshape(-1, 3)
    assert any(tuple(p) == SKELETON_COLOUR for p in near)
    # far from the figure the frame is left black
    assert np.all(img[:5, :5] == 0)


def test_the_page_embeds_the_pictures_and_says_why_each_is_shown(clip):
    tracks, est = clip
    w, h = (int(v) for v in tracks.image_size)
    frames = {i: np.full((h, w, 3), 90, np.uint8) for i, _ in pick_frames(est)}
    pictures = footage_pictures(est, tracks, frames, pick_frames(est))
    assert len(pictures) >= 4 and all(p.png.startswith(b"\x89PNG") for p in pictures)
    page = review_html(est, first_frame=1, pictures=pictures)
    assert page.count("data:image/png;base64,") == len(pictures)
    assert re.search(r"<figcaption>frame 1: [^<]*spread", page)
    assert pictures_html([]) == "" and "Footage" not in review_html(est)
    assert len(page) < 1_000_000
