"""The virtual camera's schedule keeps the paper's assumptions (section 3.2) and moves smoothly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.camera import pan_tilt_roll_matrix, rotvec_deg
from core.errors import InputError
from core.synthetic.synth_camera import (
    PAN_RANGE_DEG,
    ROLL_RANGE_DEG,
    TILT_RANGE_DEG,
    ZOOM_RATIO_RANGE,
    Spell,
    camera_rotations,
    camera_states,
    check_schedule,
    ease,
    make_schedule,
    moving_mask,
)

ALL_MOVES = ("pan", "tilt", "pan_tilt", "zoom", "rotate_zoom", "roll")
CASES = [(n, fps, kinds, seed) for n, fps in ((300, 30.0), (240, 24.0), (1200, 120.0), (900, 25.0))
         for kinds in (("pan", "tilt", "zoom"), ALL_MOVES) for seed in (0, 7)]


@pytest.mark.parametrize("n,fps,kinds,seed", CASES)
def test_paper_schedule_respects_still_and_motion_durations(n, fps, kinds, seed):
    spells = make_schedule(n, fps, kinds, seed)
    check_schedule(spells, n)  # covers 0..n-1 with inclusive ends, no gaps
    assert spells[0].kind == "still" and spells[-1].kind == "still"
    for a, b in zip(spells, spells[1:], strict=False):
        assert a.end + 1 == b.start
        assert not (a.moving and b.moving), "paper mode needs a still spell between motions"
    for s in spells:
        if s.moving:
            assert s.n_frames >= math.ceil(0.5 * fps - 1e-9)
            assert s.kind in kinds
        elif s is spells[-1]:
            assert s.n_frames >= math.ceil(0.5 * fps - 1e-9)   # the closing still is not between motions
        else:
            assert s.n_frames >= math.ceil(1.0 * fps - 1e-9)
    assert sum(s.moving for s in spells) >= 3  # 8+ s clips have room for several motions


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_continuous_schedule_has_no_still_between_motions(seed):
    spells = make_schedule(600, 30.0, ALL_MOVES, seed, continuous=True)
    check_schedule(spells, 600)
    assert spells[0].kind == "still" and spells[0].n_frames >= 30
    assert all(s.moving for s in spells[1:])
    assert all(s.n_frames >= 15 for s in spells[1:])
    assert len({s.kind for s in spells[1:]}) == len(ALL_MOVES)  # every kind shows up in 18 s
    assert all(a.kind != b.kind for a, b in zip(spells[1:], spells[2:], strict=False))


@pytest.mark.parametrize("seed", range(6))
def test_amplitudes_are_realistic_and_accumulate_within_limits(seed):
    spells = make_schedule(3000, 30.0, ALL_MOVES, seed)
    pan = tilt = roll = 0.0
    focal = 1.0
    for s in spells:
        p = s.params
        if s.kind in ("pan", "pan_tilt", "rotate_zoom"):
            assert PAN_RANGE_DEG[0] - 1e-9 <= abs(p["pan_deg"]) <= PAN_RANGE_DEG[1] + 1e-9
        if s.kind in ("tilt", "pan_tilt", "rotate_zoom"):
            assert TILT_RANGE_DEG[0] - 1e-9 <= abs(p["tilt_deg"]) <= TILT_RANGE_DEG[1] + 1e-9
        if s.kind == "roll":
            assert ROLL_RANGE_DEG[0] - 1e-9 <= abs(p["roll_deg"]) <= ROLL_RANGE_DEG[1] + 1e-9
        if s.kind in ("zoom", "rotate_zoom"):
            ratio = max(p["zoom"], 1.0 / p["zoom"])
            assert ZOOM_RATIO_RANGE[0] - 1e-9 <= ratio <= ZOOM_RATIO_RANGE[1] + 1e-9
        if s.kind == "still":
            assert p == {}
        pan += p.get("pan_deg", 0.0)
        tilt += p.get("tilt_deg", 0.0)
        roll += p.get("roll_deg", 0.0)
        focal *= p.get("zoom", 1.0)
        assert abs(pan) <= 20 + 1e-9 and abs(tilt) <= 8 + 1e-9 and abs(roll) <= 6 + 1e-9
        assert 1.0 - 1e-9 <= focal <= 1.6 + 1e-9


def test_schedule_is_reproducible_from_its_seed():
    a = make_schedule(600, 30.0, ALL_MOVES, 11)
    b = make_schedule(600, 30.0, ALL_MOVES, 11)
    c = make_schedule(600, 30.0, ALL_MOVES, 12)
    assert [s.to_dict() for s in a] == [s.to_dict() for s in b]
    assert [s.to_dict() for s in a] != [s.to_dict() for s in c]


def test_camera_states_are_smooth_and_follow_the_spells():
    fps, n = 30.0, 900
    spells = make_schedule(n, fps, ALL_MOVES, 3)
    angles, focal = camera_states(spells, n, 50.0)
    assert np.allclose(angles[0], 0.0) and focal[0] == pytest.approx(50.0)
    moving = moving_mask(spells, n)
    d_angle = np.abs(np.diff(angles, axis=0)).max(axis=1)
    d_focal = np.abs(np.diff(np.log(focal)))
    changed = np.r_[False, (d_angle > 0) | (d_focal > 0)]
    assert np.array_equal(changed, moving)          # exactly the motion spells' frames move
    for s in spells:
        sl = slice(s.start, s.end + 1)
        if not s.moving:
            assert np.ptp(angles[sl], axis=0).max() == 0 and np.ptp(focal[sl]) == 0
            continue
        # cosine profile: |second difference| <= amplitude * pi^2 / (2 n^2) per spell
        n_s = s.n_frames
        seg = np.concatenate([angles[s.start - 1:s.end + 1], angles[s.end:s.end + 1]])
        amp = np.array([abs(s.params.get(k, 0.0)) for k in ("pan_deg", "tilt_deg", "roll_deg")])
        bound = amp * np.pi ** 2 / (2 * n_s ** 2) * 1.001 + 1e-12
        assert (np.abs(np.diff(seg, 2, axis=0)) <= bound).all()
        # the spell starts and ends at rest: first and last steps are tiny compared to the peak
        step = np.abs(np.diff(angles[s.start - 1:s.end + 1], axis=0)).max(axis=1)
        if step.max() > 0:
            assert step[0] < 0.2 * step.max() and step[-1] < 0.2 * step.max()
        # the full change is reached on the last frame
        before = angles[s.start - 1]
        expect = before + np.array([s.params.get(k, 0.0) for k in ("pan_deg", "tilt_deg", "roll_deg")])
        assert np.allclose(angles[s.end], expect)
        assert focal[s.end] == pytest.approx(focal[s.start - 1] * s.params.get("zoom", 1.0))


@pytest.mark.parametrize("n,fps,moves", [(74, 30.0, 1), (297, 120.0, 1), (59, 30.0, 0), (60, 30.0, 1)])
def test_short_clips_get_a_motion_when_one_fits(n, fps, moves):
    spells = make_schedule(n, fps, ("pan", "zoom"), 0)
    check_schedule(spells, n)
    assert sum(s.moving for s in spells) == moves
    assert spells[0].n_frames >= math.ceil(fps - 1e-9) or len(spells) == 1


def test_ease_profile_rises_monotonically_to_one():
    p = ease(17)
    assert p[-1] == pytest.approx(1.0) and p[0] > 0 and (np.diff(p) > 0).all()


def test_rotations_are_pan_tilt_roll_matrices_and_identity_at_rest():
    angles = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, -5.0, 0.0], [3.0, 2.0, 1.0]])
    rot = camera_rotations(angles)
    assert np.allclose(rot[0], np.eye(3))
    assert np.allclose(rot[3], pan_tilt_roll_matrix(3.0, 2.0, 1.0))
    # a pure pan rotates about the camera's y axis by the pan angle
    rv = rotvec_deg(rot[1])
    assert abs(rv[0]) < 1e-9 and abs(rv[2]) < 1e-9 and abs(abs(rv[1]) - 10.0) < 1e-9
    rv = rotvec_deg(rot[2])
    assert abs(abs(rv[0]) - 5.0) < 1e-9


def test_bad_kinds_and_gapped_schedules_are_input_errors():
    with pytest.raises(InputError, match="unknown camera motion kind"):
        make_schedule(100, 30.0, ("pan", "dolly"))
    with pytest.raises(InputError, match="fps"):
        make_schedule(100, 0.0)
    with pytest.raises(InputError, match="gap"):
        check_schedule([Spell(0, 9, "still"), Spell(11, 19, "pan", {"pan_deg": 5.0})], 20)
    with pytest.raises(InputError, match="covers"):
        check_schedule([Spell(0, 9, "still")], 20)


def test_spell_dict_round_trip_and_validation():
    s = Spell(10, 30, "rotate_zoom", {"pan_deg": -7.5, "tilt_deg": 3.0, "zoom": 1.2})
    assert Spell.from_dict(s.to_dict()) == s
    with pytest.raises(InputError):
        Spell.from_dict({"start": 5, "end": 2, "kind": "pan"})
    with pytest.raises(InputError):
        Spell.from_dict({"start": 0, "end": 2, "kind": "spin"})


@settings(max_examples=60)
@given(n=st.integers(1, 2500), fps=st.sampled_from([12.0, 24.0, 25.0, 29.97, 30.0, 60.0, 120.0]),
                  kinds=st.lists(st.sampled_from(ALL_MOVES + ("still",)), max_size=4),
                  seed=st.integers(0, 2 ** 31), continuous=st.booleans())
def test_any_schedule_covers_the_clip_and_keeps_the_duration_rules(n, fps, kinds, seed, continuous):
    spells = make_schedule(n, fps, kinds, seed, continuous=continuous)
    check_schedule(spells, n)
    assert spells[0].kind == "still"
    moves = [s for s in spells if s.moving]
    assert all(s.kind in kinds for s in moves)
    assert all(s.n_frames >= math.ceil(0.5 * fps - 1e-9) for s in moves)
    if not continuous:
        for a, b in zip(spells, spells[1:], strict=False):
            assert not (a.moving and b.moving)
        inner = [s for s in spells[:-1] if not s.moving]
        assert all(s.n_frames >= math.ceil(fps - 1e-9) for s in inner) or not moves
    angles, focal = camera_states(spells, n, 50.0)
    assert np.isfinite(angles).all() and (focal > 0).all()
