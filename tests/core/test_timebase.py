"""The working frame rate: the same motion at 30, 60, 120 and 240 fps gives the same answer."""

from __future__ import annotations

import numpy as np
import pytest

from core.estimate import estimate
from core.evaluation.evaluate import score
from core.joint_solve.blas_threads import single_blas_thread
from core.joint_solve.pipeline import estimate_joint
from core.skeleton import segment_lengths
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.synth_camera import Spell
from core.timebase import decimation_factor, to_full_rate, to_working_rate
from core.track_cleaning import clean_tracks


def _film(fps: float, noise_px: float):
    """The built-in walk at ``fps`` under one camera schedule fixed in seconds (a pan, a tilt, a zoom)."""
    motion = load_motion("builtin:walk", fps=fps)
    n = motion.n_frames
    marks = [(0.0, "still", {}), (2.0, "pan", {"pan_deg": 12.0}), (3.0, "still", {}),
             (4.5, "tilt", {"tilt_deg": 5.0}), (5.3, "still", {}), (6.5, "zoom", {"zoom": 1.3}),
             (7.5, "still", {})]
    spells = []
    for i, (t, kind, params) in enumerate(marks):
        start = int(round(t * fps))
        end = (int(round(marks[i + 1][0] * fps)) if i + 1 < len(marks) else n) - 1
        spells.append(Spell(start, min(end, n - 1), kind, params))
    return synthesize(motion, schedule=spells, noise_px=noise_px, seed=0)


def test_decimation_factors():
    assert [decimation_factor(f, 10_000) for f in (24, 25, 30, 48, 50, 60, 100, 120, 240)] == \
        [1, 1, 1, 2, 2, 2, 3, 4, 8]
    assert decimation_factor(240, 200) == 3          # short clips keep at least 60 working frames


def test_working_frames_are_the_frames_a_slower_camera_films():
    tracks = _film(120.0, 0.0)[0]
    slow = _film(30.0, 0.0)[0]
    work = to_working_rate(tracks, 4)
    assert work.fps == 30.0 and work.n_frames == slow.n_frames
    both = np.isfinite(work.xy) & np.isfinite(slow.xy)
    assert np.median(np.abs(work.xy - slow.xy)[both]) < 0.5     # px: only the one-interval average differs


@pytest.fixture(scope="module")
def by_rate():
    out = {}
    for fps in (30.0, 60.0, 120.0, 240.0):
        tracks, truth = _film(fps, 0.0)   # noise-free: the difference is the frame rate alone
        # the solve as the working rate brings it back, before the motion cleanup changes the feet
        est = estimate(tracks, "joint", motion_cleanup=None)
        out[fps] = (tracks, truth, est)
    return out


def test_same_motion_any_frame_rate_same_proportions_and_camera(by_rate):
    base = by_rate[30.0][2].proportions_vector()
    rot30 = score(by_rate[30.0][2], by_rate[30.0][1])["rotation_error_deg"]
    for fps in (60.0, 120.0, 240.0):
        tracks, truth, est = by_rate[fps]
        assert np.mean(np.abs(est.proportions_vector() - base)) * 100 <= 0.1, fps
        assert abs(score(est, truth)["rotation_error_deg"] - rot30) <= 0.2, fps


def test_every_input_frame_gets_a_pose_with_the_same_bones(by_rate):
    tracks, _, est = by_rate[120.0]
    assert len(est.frames) == tracks.n_frames
    j3 = np.array([f.joints_3d for f in est.frames])
    lengths = segment_lengths(j3)
    # frames 0, k, 2k ... are the working frames themselves; in between, the bones keep their lengths
    assert np.max(np.ptp(lengths, axis=0) - np.ptp(lengths[::4], axis=0)) < 1e-9
    assert est.diagnostics["working_rate"]["factor"] == 4
    spells = est.diagnostics["spells"]
    assert spells[0]["start"] == 0 and spells[-1]["end"] == tracks.n_frames - 1
    assert all(a["end"] + 1 == b["start"] for a, b in zip(spells, spells[1:]))
    assert all(f.reprojection_px is not None for f in est.frames[:50])


def test_the_working_frames_come_back_unchanged_and_the_rest_lie_between_them(by_rate):
    tracks, _, est = by_rate[120.0]
    # on one BLAS thread, as core.estimate runs a method: a product summed by two threads in another
    # order differs in the 9th digit, which is not a change of frames
    with single_blas_thread():
        work = estimate_joint(to_working_rate(clean_tracks(tracks)[0], 4))
    # equal up to floating-point noise: two runs of the solver usually agree to the 13th digit, but after
    # the rest of the suite has run in the same process they were once 8e-9 degrees apart; a change of
    # frames (a shift, an interpolated working frame) moves the walking joints by centimetres and, while
    # the camera turns (12 degrees in a second), the angles by tenths of a degree
    np.testing.assert_allclose(work.proportions_vector(), est.proportions_vector(), rtol=1e-9)
    rv_work = np.array([f.rotvec_deg for f in work.frames])
    rv = np.array([f.rotvec_deg for f in est.frames])
    np.testing.assert_allclose(rv[::4], rv_work, rtol=0, atol=1e-7)
    assert np.allclose(np.array([f.joints_3d for f in est.frames[::4]]),
                       np.array([f.joints_3d for f in work.frames]), atol=1e-7)
    kept = rv[::4]                      # the in-between frames lie between their run's working frames
    lo = np.minimum(kept[:-1], kept[1:])
    hi = np.maximum(kept[:-1], kept[1:])
    for off in (1, 2, 3):
        mid = rv[off::4][:len(lo)]
        assert np.all((mid >= lo - 1e-12) & (mid <= hi + 1e-12))
    again = to_full_rate(work, 1, tracks.n_frames)
    assert again is work


def test_frames_between_and_nearest_marked_frame():
    from core.timebase.frames import frames_between, nearest_marked

    i0, i1, w = frames_between(np.array([-1.0, 0.0, 2.25, 4.0, 9.0]), 0, 4)
    np.testing.assert_array_equal(i0, [0, 0, 2, 4, 4])
    np.testing.assert_array_equal(i1, [1, 1, 3, 4, 4])
    np.testing.assert_allclose(w, [0.0, 0.0, 0.25, 0.0, 0.0])
    v = np.arange(5.0) ** 2
    np.testing.assert_allclose(v[i0] * (1 - w) + v[i1] * w, [0.0, 0.0, 4 + 0.25 * 5, 16.0, 16.0])
    marked = np.array([2, 6, 9])
    # frame 4 is a tie between 2 and 6: the earlier
    np.testing.assert_array_equal(nearest_marked(marked, np.arange(12)), [0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 2])
