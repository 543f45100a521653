"""Synchronising two views of a repeated movement (core/multiview/sync.py): an offset one cycle away from
the true one can explain the joints as well (a steady walk a cycle later is the same pose moved along, and
a camera moved along with it sees the same pictures), so the answer is said to be ambiguous, naming both
offsets and their fits; scene points both views track under one name settle it, and given offsets are
taken as they are."""

from __future__ import annotations

import numpy as np
import pytest

from core.multiview import estimate_multiview
from core.multiview.sync import AMBIGUITY_MARGIN, ambiguity_warning, frame_offset, static_pairs
from core.multiview.synth import film_views, ring_cameras, steady_repeat
from core.synthetic.motion import Motion, load_motion
from core.tracks import StaticTracks


def _steady_walk(n: int) -> tuple[Motion, int]:
    """The built-in walk made exactly periodic (a perfectly steady walker) and its cycle in frames."""
    return steady_repeat(load_motion("builtin:walk", max_frames=200), n, start=60)


def _scene_marks(motion, cams, n=8, seed=0, floor_only=False):
    """``n`` still scene points (corners of furniture and walls: not all on one plane; or marks on the floor),
    tracked in both views under the same names."""
    rng = np.random.default_rng(seed)
    middle = motion.joints.reshape(-1, 3).mean(0)
    pts = middle + np.c_[rng.uniform(-3, 3, n), np.zeros(n), rng.uniform(-3, 3, n)]
    pts[:, 1] = motion.joints[..., 1].min() + (0.0 if floor_only else rng.uniform(0.0, 2.5, n))
    out = []
    for cam in cams:
        uv = cam.project(pts[None])[0]
        xy = np.repeat(uv[None], motion.n_frames, 0) + rng.normal(0, 1.0, (motion.n_frames, n, 2))
        out.append(StaticTracks([f"mark_{k}" for k in range(n)], xy, np.ones((motion.n_frames, n))))
    return out


@pytest.fixture(scope="module")
def steady():
    motion, period = _steady_walk(220)
    cams = ring_cameras(motion, 2, seed=5)
    full = film_views(motion, cams, noise_px=1.0, seed=5)
    marks = _scene_marks(motion, cams)
    floor = _scene_marks(motion, cams, floor_only=True)
    true = 9                                     # the second view started 9 frames later

    def cut(view, start, st=None):
        static = None if st is None else StaticTracks(st.names, st.xy[start:start + 180], st.conf[start:start + 180])
        return view.replaced(xy=view.xy[start:start + 180], conf=view.conf[start:start + 180], static=static)

    plain = [cut(full[0], 20), cut(full[1], 20 - true)]
    marked = [cut(full[0], 20, marks[0]), cut(full[1], 20 - true, marks[1])]
    on_floor = [cut(full[0], 20, floor[0]), cut(full[1], 20 - true, floor[1])]
    return plain, marked, true, period, cams, on_floor


def test_a_cycle_away_fits_as_well_and_is_said(steady):
    plain, _, true, period, cams, _ = steady
    best, report = frame_offset(*plain)
    assert report["ambiguous"] and report["static_points"] == 0
    # the two answers lie a whole number of cycles from the true offset (which may be either, or a third
    # answer as good), both within the margin
    for d in (best, report["second_offset"]):
        assert min((d - true) % period, period - (d - true) % period) <= 2, (d, true, period)
    assert abs(best - report["second_offset"]) >= period - 2
    assert report["second_px"] <= report["error_px"] * (1 + AMBIGUITY_MARGIN)
    text = ambiguity_warning("view 2", "view 1", report, 30.0)
    assert f"{best:+d} frames fits {report['error_px']:.2f} px" in text
    assert f"{report['second_offset']:+d} frames" in text and "--offsets" in text
    est = estimate_multiview(plain, cameras=cams)
    said = [w for w in est.diagnostics["warnings"] if "is ambiguous" in w]
    assert len(said) == 1 and est.diagnostics["sync"][0]["ambiguous"]
    given = estimate_multiview(plain, cameras=cams, offsets=[0, true])          # a given offset is taken
    assert given.diagnostics["frame_offsets"] == [0, true]
    assert not any("is ambiguous" in w for w in given.diagnostics["warnings"])


def test_scene_points_both_views_track_settle_it(steady):
    _, marked, true, period, _, on_floor = steady
    a, b, names = static_pairs(*marked)
    assert len(names) == 8 and a.shape == b.shape == (8, 2)
    best, report = frame_offset(*marked, max_s=1.5)
    assert best == true and report["static_points"] == 8 and not report["static_refused"]
    assert not report["ambiguous"] and report["second_px"] > 2 * report["error_px"]
    # marks on the floor alone (one plane) leave the matrix free: they are refused, the joints decide alone
    best, report = frame_offset(*on_floor, max_s=1.5)
    assert report["static_refused"] and report["static_points"] == 0 and report["ambiguous"]


def test_a_clear_answer_is_not_called_ambiguous():
    motion = load_motion("builtin:walk", max_frames=200)
    cams = ring_cameras(motion, 2, seed=1)
    full = film_views(motion, cams, noise_px=1.0, seed=1)
    v1 = full[0].replaced(xy=full[0].xy[30:180], conf=full[0].conf[30:180])
    v2 = full[1].replaced(xy=full[1].xy[24:174], conf=full[1].conf[24:174])
    best, report = frame_offset(v1, v2)
    assert best == 6 and not report["ambiguous"]
    assert ambiguity_warning("b", "a", report, 30.0) is None
