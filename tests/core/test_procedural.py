"""The built-in motions: rigid, symmetric, really walking/running (or standing), with exact contacts."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import InputError
from core.skeleton import (
    ANKLE_HEIGHT_FRACTION,
    CLASS_INDEX,
    JOINT_INDEX,
    SEGMENT_CLASS,
    segment_lengths,
    standing_height,
)
from core.synthetic.motion import load_motion
from core.synthetic.procedural import BUILTIN_MOTIONS, builtin_motion
from core.synthetic.rigid_figure import foot_contacts


@pytest.fixture(scope="module", params=BUILTIN_MOTIONS)
def motion(request):
    return builtin_motion(request.param)


@pytest.fixture(scope="module", params=[m for m in BUILTIN_MOTIONS if m != "stand"])
def gait(request):
    """The built-in motions that travel: the walk and the run."""
    return builtin_motion(request.param)


def _runs(mask):
    """(start, end) of every run of True, end exclusive."""
    padded = np.concatenate([[False], mask, [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2], edges[1::2], strict=True))


def test_walk_run_and_stand_exist():
    assert {"walk", "run", "stand"} <= set(BUILTIN_MOTIONS)


def test_load_motion_builtin_prefix():
    m = load_motion("builtin:walk", max_frames=20)
    assert m.n_frames == 20 and m.name == "walk"


def test_shapes_and_default_lengths(motion):
    assert motion.joints.shape == (motion.n_frames, 17, 3)
    assert motion.contacts.shape == (motion.n_frames, 2) and motion.contacts.dtype == bool
    assert motion.fps == 30.0
    expected_s = {"walk": 10.0, "run": 6.0}.get(motion.name)
    if expected_s is not None:
        assert motion.n_frames == pytest.approx(expected_s * 30, abs=1)
    assert np.all(np.isfinite(motion.joints))


def test_segments_are_rigid_and_symmetric(motion):
    lengths = segment_lengths(motion.joints)
    expected = motion.class_lengths[list(SEGMENT_CLASS)]
    np.testing.assert_allclose(lengths, np.broadcast_to(expected, lengths.shape), rtol=0, atol=1e-9)


@pytest.mark.parametrize("height", [1.5, 1.75, 1.92])
def test_height_is_respected(height):
    m = builtin_motion("walk", height_m=height, fps=10)
    assert standing_height(m.class_lengths) == pytest.approx(height, rel=1e-12)


def test_planted_ankles_are_exactly_still_on_the_floor(gait):
    ankle_y = ANKLE_HEIGHT_FRACTION * standing_height(gait.class_lengths)
    for col, side in enumerate("lr"):
        ankle = gait.joints[:, JOINT_INDEX[f"{side}_ankle"]]
        runs = _runs(gait.contacts[:, col])
        assert len(runs) >= 4, f"{side} foot is planted only {len(runs)} times"
        for start, end in runs:
            np.testing.assert_array_equal(ankle[start:end], np.broadcast_to(ankle[start], (end - start, 3)))
            assert ankle[start, 1] == pytest.approx(ankle_y, abs=1e-12)
        # nothing goes below the floor and swinging feet are lifted
        assert ankle[:, 1].min() >= ankle_y - 1e-12
        assert ankle[~gait.contacts[:, col], 1].max() > ankle_y + 0.03


def test_several_steps_each_second(gait):
    strikes = sum(len(_runs(gait.contacts[:, col])) for col in range(2))
    duration = gait.n_frames / gait.fps
    assert strikes / duration >= 1.5


def test_run_has_flight_and_walk_has_single_support():
    run = builtin_motion("run")
    assert (~run.contacts.any(axis=1)).mean() > 0.2
    walk = builtin_motion("walk")
    single = walk.contacts[:, 0] ^ walk.contacts[:, 1]
    assert single.mean() > 0.6


def test_figure_travels_and_turns(gait):
    pelvis = gait.joints[:, JOINT_INDEX["pelvis"]]
    travel = np.linalg.norm(pelvis[-1, [0, 2]] - pelvis[0, [0, 2]])
    assert travel > 5.0
    velocity = np.diff(pelvis[:, [0, 2]], axis=0)
    heading = np.unwrap(np.arctan2(velocity[:, 0], velocity[:, 1]))
    # smooth over a gait cycle so the sway does not count as turning
    window = int(gait.fps)
    smooth = np.convolve(heading, np.ones(window) / window, mode="valid")
    assert np.degrees(smooth.max() - smooth.min()) > 45
    # both a left and a right turn
    turn_rate = np.diff(smooth)
    assert turn_rate.max() > 0 and turn_rate.min() < 0


def test_arms_swing_and_pelvis_bobs(gait):
    J = JOINT_INDEX
    pelvis = gait.joints[:, J["pelvis"]]
    assert np.ptp(pelvis[:, 1]) > 0.01
    for side in "lr":
        wrist_rel = gait.joints[:, J[f"{side}_wrist"]] - gait.joints[:, J["thorax"]]
        assert np.ptp(np.linalg.norm(wrist_rel - wrist_rel.mean(axis=0), axis=1)) > 0.05


def test_knees_bend_forward(gait):
    J = JOINT_INDEX
    pelvis = gait.joints[:, J["pelvis"]]
    forward = np.gradient(pelvis[:, [0, 2]], axis=0)
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    for side in "lr":
        hip, knee, ankle = (gait.joints[:, J[f"{side}_{n}"]] for n in ("hip", "knee", "ankle"))
        mid = 0.5 * (hip + ankle)
        ahead = np.sum((knee - mid)[:, [0, 2]] * forward, axis=1)
        assert (ahead > -1e-9).mean() > 0.95


def test_foot_contacts_detects_generated_contacts(gait):
    detected = foot_contacts(gait.joints, gait.fps)
    assert detected.shape == gait.contacts.shape
    agreement = (detected == gait.contacts).mean()
    assert agreement > 0.85


def test_fps_is_honoured():
    m = builtin_motion("run", fps=60)
    assert m.fps == 60 and m.n_frames == 360


def test_class_lengths_are_plausible():
    m = builtin_motion("walk")
    c = m.class_lengths
    assert c[CLASS_INDEX["thigh"]] > c[CLASS_INDEX["forearm"]] > c[CLASS_INDEX["hip"]]


@pytest.mark.parametrize("bad", [dict(name="moonwalk"), dict(name="walk", height_m=-1), dict(name="walk", fps=0)])
def test_bad_requests_raise_input_error(bad):
    with pytest.raises(InputError):
        builtin_motion(**bad)


def test_standing_figure_keeps_both_feet_planted_and_shifts_its_weight():
    m = builtin_motion("stand")
    J = JOINT_INDEX
    assert m.contacts.all()
    ankle_y = ANKLE_HEIGHT_FRACTION * standing_height(m.class_lengths)
    for side in "lr":
        ankle = m.joints[:, J[f"{side}_ankle"]]
        np.testing.assert_array_equal(ankle, np.broadcast_to(ankle[0], ankle.shape))
        assert ankle[0, 1] == pytest.approx(ankle_y, abs=1e-12)
    # the pelvis sways from one foot towards the other and back, staying between them
    left, right = m.joints[0, J["l_ankle"]], m.joints[0, J["r_ankle"]]
    across = (left - right) / np.linalg.norm(left - right)
    sway = (m.joints[:, J["pelvis"]] - 0.5 * (left + right)) @ across
    assert np.ptp(sway) > 0.05 and np.abs(sway).max() < 0.5 * np.linalg.norm(left - right)
    assert sway.max() > 0 > sway.min()
    # legs nearly straight, arms hanging: wrists below elbows below shoulders
    leg = m.class_lengths[CLASS_INDEX["thigh"]] + m.class_lengths[CLASS_INDEX["shank"]]
    for side in "lr":
        reach = np.linalg.norm(m.joints[:, J[f"{side}_ankle"]] - m.joints[:, J[f"{side}_hip"]], axis=1)
        assert reach.min() > 0.97 * leg
        y = {n: m.joints[:, J[f"{side}_{n}"], 1] for n in ("shoulder", "elbow", "wrist")}
        assert np.all(y["wrist"] < y["elbow"]) and np.all(y["elbow"] < y["shoulder"])
