"""Holding a sliding foot still over a span of frames: the ankle kept at one place, the leg bent to reach it,
nothing else moved, no pop either side."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core import cli
from core.errors import InputError
from core.motion_cleanup.foot_lock import LEGS, two_bone_ik
from core.motion_cleanup.foot_plant import plant_foot, stance_span
from core.result import read_estimate_json, write_estimate_json
from core.runs import runs
from core.skeleton import JOINT_INDEX, SEGMENTS
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import truth_as_estimate

ANKLE, KNEE = JOINT_INDEX["l_ankle"], JOINT_INDEX["l_knee"]


@pytest.fixture(scope="module")
def walk():
    """The truth of a walk filmed by a panning camera, shaped as an estimate, and the left foot's first contact
    long enough to plant (the truth's stance)."""
    _, truth = synthesize(load_motion("builtin:walk", max_frames=90), kinds=("pan",), seed=4)
    est = truth_as_estimate(truth)
    contact = np.array([s == "l" for s in truth.stance])
    first, end = next((a, b) for a, b in runs(contact) if b - a >= 8 and a >= 5 and b <= 85)
    return est, truth, int(first), int(end) - 1


def _joints(est):
    return np.array([fr.joints_3d for fr in est.frames], dtype=float)


def _lengths(joints):
    return np.linalg.norm(joints[:, [c for _, c in SEGMENTS]] - joints[:, [p for p, _ in SEGMENTS]], axis=-1)


def _sliding(est, first, last, speed_m_s=0.6):
    """``est`` with its left ankle sliding away along its line of sight over the contact and the frames
    after it (as a solve lets a standing foot slide in depth), the leg bent to follow, lengths kept."""
    j = _joints(est)
    fps = est.diagnostics["fps"]
    t = np.clip(np.arange(len(j)) - first, 0, None)[:, None] / fps
    ray = j[:, ANKLE] / np.linalg.norm(j[:, ANKLE], axis=1, keepdims=True)
    hip, knee, ankle = LEGS[0]
    j[:, knee], j[:, ankle] = two_bone_ik(j[:, hip], j[:, knee], j[:, ankle], j[:, ankle] + speed_m_s * t * ray)
    frames = [dataclasses.replace(fr, joints_3d=p.tolist()) for fr, p in zip(est.frames, j, strict=True)]
    return dataclasses.replace(est, frames=frames)


def test_a_planted_foot_stays_at_one_place_and_only_its_leg_moves(walk):
    est, _, first, last = walk
    slid = _sliding(est, first, last)
    fixed, report = plant_foot(slid, "l", first, last)
    before, after = _joints(slid), _joints(fixed)
    held = after[first:last + 1, ANKLE]
    # at one place over the span, but where a straight leg cannot reach it
    off = np.linalg.norm(held - np.array(report["place"]), axis=1)
    assert report["slide_m"] > 0.1 and report["unreached_m"] < 0.01
    assert np.all(off <= report["unreached_m"] + 1e-9) and np.median(off) < 1e-9
    np.testing.assert_allclose(_lengths(after), _lengths(before), atol=1e-9)
    moved = np.linalg.norm(after - before, axis=-1)
    assert np.all(np.delete(moved, [ANKLE, KNEE], axis=1) == 0)               # nothing but the knee and ankle
    blend = 3                                                                  # 0.1 s at 30 fps
    outside = np.r_[0:first - blend, last + blend + 1:len(before)]
    assert np.all(moved[outside] == 0)
    # eased in and out: the ankle's offset to the place (half the slide and more at the span's ends) is spread
    # over the frames either side instead of taken in one step
    step = np.linalg.norm(np.diff(after[:, ANKLE], axis=0), axis=1)
    own = np.linalg.norm(np.diff(before[:, ANKLE], axis=0), axis=1)
    edges = np.r_[first - blend - 1:first, last:last + blend + 1]
    assert np.max(step[edges] - own[edges]) < 0.3 * report["slide_m"]
    assert fixed.diagnostics["planted_feet"][-1] == report
    assert slid.frames[first + 2].joints_3d == before[first + 2].tolist()       # the estimate given is unchanged


def test_the_offered_span_is_the_contact_around_the_frame(walk):
    est, truth, first, last = walk
    a, b = stance_span(est, "l", (first + last) // 2)
    assert abs(a - first) <= 3 and abs(b - last) <= 3
    swing = next(i for i in range(last + 1, len(truth.stance)) if truth.stance[i] == "r"
                 and truth.stance[i - 1] == "r" and truth.stance[i + 1] == "r")
    with pytest.raises(InputError, match="not standing on frame"):
        stance_span(est, "l", swing + 2)


@pytest.mark.parametrize("foot, first, last, message", [
    ("x", 3, 9, "no foot"), ("l", 5, 400, "not in the estimate"), ("r", 9, 3, "not in the estimate")])
def test_bad_input_is_one_line(walk, foot, first, last, message):
    with pytest.raises(InputError, match=message):
        plant_foot(walk[0], foot, first, last)


def test_frames_without_3d_joints_are_one_line(walk):
    est = walk[0]
    frames = list(est.frames)
    frames[7] = dataclasses.replace(frames[7], joints_3d=None)
    with pytest.raises(InputError, match="no 3D joints on frame 7"):
        plant_foot(dataclasses.replace(est, frames=frames), "l", 5, 9)


def test_the_command_line_writes_the_planted_estimate(walk, tmp_path, capsys):
    est, _, first, last = walk
    slid = _sliding(est, first, last, speed_m_s=0.3)     # still counted as standing (the release is 0.5 m/s)
    write_estimate_json(slid, tmp_path / "r.json")
    mid = (first + last) // 2
    assert cli.main(["plant-foot", str(tmp_path / "r.json"), "--foot", "l", "--at", str(mid),
                     "--out", str(tmp_path / "fixed.json")]) == 0
    fixed = read_estimate_json(tmp_path / "fixed.json")
    a, b = fixed.diagnostics["planted_feet"][0]["first"], fixed.diagnostics["planted_feet"][0]["last"]
    assert a <= mid <= b
    held = _joints(fixed)[a:b + 1, ANKLE]
    assert np.median(np.linalg.norm(held - np.median(held, axis=0), axis=1)) < 1e-4
    assert "held still on frames" in capsys.readouterr().err
    code = cli.main(["plant-foot", str(tmp_path / "r.json"), "--foot", "l", "--frames", "5-999",
                     "--out", str(tmp_path / "bad.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "not in the estimate" in err[0]
    assert not (tmp_path / "bad.json").exists()


def test_a_place_the_body_walks_away_from_is_reported_and_warned_of(walk, tmp_path, capsys):
    est = walk[0]
    _, report = plant_foot(est, "l", 0, 89)           # a whole walk: the body leaves the place behind
    assert report["unreached_m"] > 0.5
    write_estimate_json(est, tmp_path / "r.json")
    assert cli.main(["plant-foot", str(tmp_path / "r.json"), "--foot", "l", "--frames", "0-89",
                     "--out", str(tmp_path / "fixed.json")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and err[1].startswith("warning: the held place lay") and "beyond the leg's reach" in err[1]
    first, last = walk[2], walk[3]
    assert plant_foot(_sliding(est, first, last), "l", first, last)[1]["unreached_m"] < 0.02


def _drifting(est, first, speed_m_s=3.0):
    """``est`` with the whole figure drifting away along the pelvis' line of sight from ``first`` on (as a solve
    reads a zoom as the person coming nearer or going away), its pose and the pelvis' image kept."""
    j = _joints(est)
    t = np.clip(np.arange(len(j)) - first, 0, None) / est.diagnostics["fps"]
    ray = j[:, 0] / np.linalg.norm(j[:, 0], axis=1, keepdims=True)
    j = j + (speed_m_s * t[:, None] * ray)[:, None, :]
    frames = [dataclasses.replace(fr, joints_3d=p.tolist()) for fr, p in zip(est.frames, j, strict=True)]
    return dataclasses.replace(est, frames=frames)


def test_a_body_that_drifted_from_the_foot_is_slid_back_along_its_line_of_sight(walk):
    est, _, first, last = walk
    drifted = _drifting(est, first)
    leg_only = plant_foot(drifted, "l", first, last)
    before, after = _joints(drifted), _joints(leg_only[0])
    report = leg_only[1]
    assert report["body_slide_m"] > 0.05 and report["unreached_m"] < 0.01       # the leg reaches once slid back
    held = after[first:last + 1, ANKLE]
    assert np.median(np.linalg.norm(held - np.array(report["place"]), axis=1)) < 1e-6
    # a rigid move along the pelvis' ray: its place in the picture and every joint but the leg's knee and
    # ankle relative to it as they were
    ray = lambda j: j[:, 0] / np.linalg.norm(j[:, 0], axis=1, keepdims=True)   # noqa: E731
    np.testing.assert_allclose(ray(after), ray(before), atol=1e-12)
    rest = [k for k in range(17) if k not in (ANKLE, KNEE)]
    np.testing.assert_allclose((after - after[:, :1])[:, rest], (before - before[:, :1])[:, rest], atol=1e-9)
    np.testing.assert_allclose(_lengths(after), _lengths(before), atol=1e-9)
    assert plant_foot(est, "l", first, last)[1]["body_slide_m"] == 0.0          # a reachable place: the leg alone
