"""Where background features may be seeded and which are kept (core.background_tracking): the pure half
of Track Background; Blender's detector and tracker are tested in tests/blender/test_background_tracking.py."""

from __future__ import annotations

import numpy as np
import pytest

from core.background_tracking import (
    BackgroundSettings,
    clean_background,
    detection_frames,
    inside_boxes,
    off_the_scene_motion,
    person_boxes,
    pick_seeds,
    static_tracks,
)
from core.errors import InputError
from core.tracks import Tracks

SIZE = (720.0, 480.0)


def _figure(n=5, missing=()):
    """A stick figure 200 px tall standing at x 300-340, y 100-300; no joint seen in the ``missing`` frames."""
    xy = np.zeros((n, 17, 2))
    xy[..., 0] = np.linspace(300, 340, 17)
    xy[..., 1] = np.linspace(100, 300, 17)
    xy[:, :, 0] += np.arange(n)[:, None] * 10.0            # walking right, 10 px a frame
    conf = np.ones((n, 17))
    for f in missing:
        xy[f] = np.nan
        conf[f] = 0.0
    return Tracks(xy=xy, conf=conf, fps=30.0, image_size=SIZE)


def test_the_person_box_is_the_joints_extent_widened_and_borrowed_where_no_joint_is_seen():
    boxes = person_boxes(_figure(missing=(1, 4)), margin=0.1)
    np.testing.assert_allclose(boxes[0], [300 - 20, 100 - 20, 340 + 20, 300 + 20])    # 0.1 x 200 px
    np.testing.assert_allclose(boxes[2], boxes[0] + [20, 0, 20, 0])
    np.testing.assert_allclose(boxes[1], boxes[0])        # nearest frame with joints (0 and 2 tie: the earlier)
    np.testing.assert_allclose(boxes[4], boxes[3])
    with pytest.raises(InputError, match="no joint"):
        person_boxes(_figure(n=2, missing=(0, 1)))


def test_inside_boxes_treats_unseen_points_as_outside():
    boxes = np.array([[0.0, 0.0, 10.0, 10.0], [20.0, 20.0, 30.0, 30.0]])
    xy = np.array([[[5.0, 5.0], [np.nan, np.nan]], [[5.0, 5.0], [25.0, 21.0]]])
    np.testing.assert_array_equal(inside_boxes(xy, boxes), [[True, False], [False, True]])


@pytest.mark.parametrize("fps", [24.0, 30.0, 60.0, 120.0, 240.0])
def test_looks_for_features_are_timed_in_seconds(fps):
    seconds = 3.0
    frames = detection_frames(int(seconds * fps), fps, every_s=0.5)
    np.testing.assert_allclose(np.array(frames) / fps, np.arange(0.0, 3.0, 0.5))


def test_no_look_on_the_last_frame():
    assert detection_frames(1, 30.0) == []
    assert detection_frames(17, 30.0, every_s=0.5) == [0, 15] and detection_frames(16, 30.0, every_s=0.5) == [0]


def test_seeds_keep_off_the_person_the_edge_and_the_points_held():
    box = np.array([300.0, 100.0, 400.0, 400.0])
    cands = np.array([[350.0, 200.0],     # on the person
                      [5.0, 240.0],       # on the edge
                      [100.0, 100.0],
                      [110.0, 105.0],     # too near the one before
                      [600.0, 60.0],      # too near a held point
                      [600.0, 400.0],
                      [120.0, 400.0]])
    live = np.array([[610.0, 70.0]])
    chosen = pick_seeds(cands, box, live, SIZE, want=10, min_separation_px=36.0, edge_px=14.0)
    assert sorted(chosen) == [2, 5, 6] or sorted(chosen) == [3, 5, 6]
    assert 0 not in chosen and 1 not in chosen and 4 not in chosen
    # no more than wanted with the held ones, the farthest from everything held first
    two = pick_seeds(cands, box, live, SIZE, want=2, min_separation_px=36.0, edge_px=14.0)
    assert len(two) == 1
    assert pick_seeds(cands, box, np.zeros((4, 2)) + 650, SIZE, want=4, min_separation_px=36.0, edge_px=14.0) == []


def test_seeds_spread_over_the_picture():
    rng = np.random.default_rng(0)
    cands = rng.uniform([20, 20], [700, 460], (400, 2))
    box = np.array([330.0, 140.0, 390.0, 340.0])
    chosen = cands[pick_seeds(cands, box, np.zeros((0, 2)), SIZE, want=8, min_separation_px=36.0, edge_px=14.0)]
    assert len(chosen) == 8
    gaps = np.linalg.norm(chosen[:, None] - chosen[None], axis=-1)[np.triu_indices(8, 1)]
    assert gaps.min() > 100.0                               # a random 8 of them would sit far closer
    assert {bool(x < 360) for x in chosen[:, 0]} == {True, False}


def test_a_feature_is_cut_where_the_person_passes_and_brief_ones_dropped():
    n = 30
    boxes = np.tile([300.0, 100.0, 400.0, 400.0], (n, 1))
    xy = np.full((n, 3, 2), np.nan)
    xy[:, 0] = [[100.0, 100.0]]                            # far off the person all along: kept whole
    xy[:, 1] = np.stack([np.linspace(200, 380, n), np.full(n, 200.0)], axis=1)   # runs into the person
    xy[:5, 2] = [[600.0, 50.0]]                            # followed 5 frames only (1/6 s at 30 fps)
    cleaned, kept, report = clean_background(xy, boxes, fps=30.0, settings=BackgroundSettings(min_track_s=0.3))
    np.testing.assert_array_equal(kept, [True, True, False])
    assert np.isfinite(cleaned[:, 0, 0]).all()
    entered = int(np.argmax(xy[:, 1, 0] >= 300))
    assert np.isfinite(cleaned[:entered, 1, 0]).all() and np.isnan(cleaned[entered:, 1, 0]).all()
    assert np.isnan(cleaned[:, 2]).all()
    assert (report.kept, report.cut, report.dropped) == (2, 1, 1)
    assert "2 background tracks" in report.summary()
    # the same 5 frames at 10 fps are half a second: kept
    _, kept10, _ = clean_background(xy, boxes, fps=10.0, settings=BackgroundSettings(min_track_s=0.3))
    assert kept10[2]


def test_a_feature_that_leaves_the_scenes_motion_is_marked_where_it_does():
    rng = np.random.default_rng(1)
    n, k = 20, 8
    start = rng.uniform([50, 50], [670, 430], (k, 2))
    xy = np.empty((n, k, 2))
    for i in range(n):                                      # a pan with a slow zoom: an affine step per frame
        s, t = 1.0 + 0.004 * i, np.array([-6.0 * i, 1.5 * i])
        xy[i] = (start - [360, 240]) * s + [360, 240] + t
    xy += rng.normal(0.0, 0.2, xy.shape)                    # the tracker's own jitter
    xy[12:, 3] += [9.0, -4.0]                               # jumps to a look-alike 10 px away at frame 12
    xy[:5, 6] = np.nan                                      # found later: judged from when it is seen
    off = off_the_scene_motion(xy, limit_px=2.9)
    assert off[12, 3] and off.sum() == 1                    # only the jump itself: the step after is the scene's
    # a jump that half the features make is the scene's own motion: nobody is marked
    half = xy.copy()
    half[12:, :4] += [9.0, -4.0]
    assert not off_the_scene_motion(half, limit_px=2.9).any()
    # three features in both frames cannot be judged
    assert not off_the_scene_motion(xy[:, :3], limit_px=2.9).any()


def test_clean_background_cuts_a_jump_from_there_on():
    n = 20
    rng = np.random.default_rng(2)
    xy = np.repeat(rng.uniform([50, 50], [250, 430], (1, 6, 2)), n, axis=0) + np.arange(n)[:, None, None] * [3.0, 0.0]
    xy[8:, 2] += [15.0, 0.0]
    boxes = np.tile([600.0, 0.0, 700.0, 100.0], (n, 1))
    cleaned, kept, report = clean_background(xy, boxes, fps=10.0, image_width=720.0)   # 8 frames: kept
    assert np.isfinite(cleaned[:8, 2, 0]).all() and np.isnan(cleaned[8:, 2, 0]).all()
    assert report.jumped == 1 and kept.all()
    untouched, _, report = clean_background(xy, boxes, fps=10.0)          # no picture width: no judging
    assert report.jumped == 0 and np.isfinite(untouched).all()


def test_kept_features_become_static_tracks():
    xy = np.full((4, 2, 2), np.nan)
    xy[:, 0] = [[10.0, 20.0]]
    xy[2:, 1] = [[30.0, 40.0]]
    st = static_tracks(xy, ["bg 1", "bg 2"])
    np.testing.assert_array_equal(st.present, [[1, 0], [1, 0], [1, 1], [1, 1]])
    assert static_tracks(np.zeros((4, 0, 2)), []) is None


@pytest.mark.parametrize("bad", [dict(want=0), dict(every_s=0.0), dict(min_track_s=-1.0), dict(person_margin=0.6),
                                 dict(edge_share=float("nan")), dict(jump_share=-0.1)])
def test_settings_out_of_range_are_refused(bad):
    with pytest.raises(InputError):
        BackgroundSettings(**bad)
