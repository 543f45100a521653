"""Flipping a bone's depth over a span of frames: the picture and the lengths kept, the limb put right."""

from __future__ import annotations

import numpy as np
import pytest

from core import cli
from core.camera import rotation_matrix
from core.errors import InputError
from core.joint_solve.taylor import child_candidates, reconstruct
from core.motion_cleanup.depth_flip import flip_depth
from core.result import read_estimate_json, write_estimate_json
from core.self_check.reprojection import camera_points, project_in_front
from core.skeleton import JOINT_INDEX, SEGMENTS, segment_lengths_from_classes
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import truth_as_estimate


@pytest.fixture(scope="module")
def filmed():
    """The truth of a walk filmed by a panning, zooming camera, shaped as an estimate, with its tracks."""
    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=60), kinds=("pan", "zoom"), seed=3)
    return truth_as_estimate(truth), tracks, truth


def _joints(est):
    return np.array([fr.joints_3d for fr in est.frames], dtype=float)


def _picture(est, tracks):
    cam, focal = camera_points(est)
    return project_in_front(cam, focal, tracks.image_size)[0]


def _lengths(joints):
    return np.linalg.norm(joints[:, [c for _, c in SEGMENTS]] - joints[:, [p for p, _ in SEGMENTS]], axis=-1)


def test_a_flip_keeps_the_picture_and_every_length_and_touches_only_its_frames(filmed):
    est, tracks, _ = filmed
    fixed, report = flip_depth(est, "l_wrist", 10, 29)
    before, after = _joints(est), _joints(fixed)
    assert report["frames"] + report["in_plane"] == 20 and report["frames"] > 15
    np.testing.assert_allclose(_picture(fixed, tracks), _picture(est, tracks), atol=1e-6)
    np.testing.assert_allclose(_lengths(after), _lengths(before), atol=1e-9)
    outside = np.r_[0:10, 30:60]
    np.testing.assert_array_equal(after[outside], before[outside])
    moved = np.linalg.norm(after - before, axis=-1)[10:30]
    wrist, elbow = JOINT_INDEX["l_wrist"], JOINT_INDEX["l_elbow"]
    assert moved[:, wrist].max() > 0.05                     # the forearm's end went to its other side
    assert np.all(np.delete(moved, wrist, axis=1) == 0)     # nothing else: the wrist ends the chain
    assert np.all(moved[:, elbow] == 0)
    assert est.frames[12].joints_3d == before[12].tolist()  # the estimate given is not changed
    assert fixed.diagnostics["depth_flips"][-1] == report


def _taylor(truth, flipped: int, span: slice):
    """The truth's joints in each frame's camera axes built by Taylor's construction from its rays, lengths and
    pelvis depth, with the segment ``flipped`` given the wrong depth sign on the frames ``span``: what a wrong
    sign in the solve looks like, made without the code under test."""
    est = truth_as_estimate(truth)
    cam, _ = camera_points(est)
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    seg_len = segment_lengths_from_classes(truth.class_lengths_m)
    signs = np.empty((len(cam), len(SEGMENTS)))
    for s, (p, c) in enumerate(SEGMENTS):
        near, far, _ = child_candidates(cam[:, p], rays[:, c], seg_len[s])
        signs[:, s] = np.where(np.linalg.norm(cam[:, c] - far, axis=-1) < np.linalg.norm(cam[:, c] - near, axis=-1),
                               1.0, -1.0)
    assert np.allclose(reconstruct(rays, truth.class_lengths_m, cam[:, 0, 2], signs), cam, atol=1e-9)
    signs[span, flipped] *= -1.0
    wrong = reconstruct(rays, truth.class_lengths_m, cam[:, 0, 2], signs)
    R = rotation_matrix(np.array([fr.rotvec_deg for fr in est.frames]))
    for fr, joints, r in zip(est.frames, wrong, R, strict=True):
        fr.joints_3d = (joints @ r).tolist()                # back to frame 0's axes
    return est


def test_a_limb_solved_on_its_wrong_side_comes_back_to_the_truth(filmed):
    _, tracks, truth = filmed
    knee = JOINT_INDEX["l_knee"]
    thigh = next(s for s, (_, c) in enumerate(SEGMENTS) if c == knee)
    wrong = _taylor(truth, thigh, slice(20, 40))
    error = np.linalg.norm(_joints(wrong) - truth.joints_3d, axis=-1)
    assert error[20:40, knee].max() > 0.05 and error[20:40, JOINT_INDEX["l_ankle"]].max() > 0.05
    assert error[:20].max() < 1e-9
    fixed, report = flip_depth(wrong, "l_knee", 20, 39)
    # the knee back on its side, the shin keeping its own sign from the knee's new place: the truth again
    np.testing.assert_allclose(_joints(fixed), truth.joints_3d, atol=1e-7)
    np.testing.assert_allclose(_picture(fixed, tracks), _picture(wrong, tracks), atol=1e-6)
    assert report["frames"] + report["in_plane"] == 20


def test_bad_requests_are_one_line_input_errors(filmed):
    est, _, _ = filmed
    for bone, first, last, words in (("l_toe", 0, 5, "no bone ends at"), ("pelvis", 0, 5, "no bone ends at"),
                                     ("l_wrist", 50, 70, "not in the estimate"), ("l_wrist", 9, 3, "not in")):
        with pytest.raises(InputError, match=words) as info:
            flip_depth(est, bone, first, last)
        assert "\n" not in str(info.value)
    flat = truth_as_estimate(filmed[2])
    for fr in flat.frames:
        fr.joints_3d = None
    with pytest.raises(InputError, match="no 3D joints"):
        flip_depth(flat, "l_wrist", 0, 5)


def test_flip_depth_command_writes_the_corrected_estimate(filmed, tmp_path, capsys):
    est, _, _ = filmed
    write_estimate_json(est, tmp_path / "r.json")
    code = cli.main(["flip-depth", str(tmp_path / "r.json"), "--bone", "r_ankle", "--frames", "5-14",
                     "--out", str(tmp_path / "fixed.json")])
    assert code == 0
    fixed = read_estimate_json(tmp_path / "fixed.json")
    expected, _ = flip_depth(est, "r_ankle", 5, 14)
    np.testing.assert_allclose(_joints(fixed), _joints(expected), atol=1e-5)
    assert fixed.diagnostics["depth_flips"][0]["bone"] == "r_ankle"
    assert "flipped in depth" in capsys.readouterr().err
    code = cli.main(["flip-depth", str(tmp_path / "r.json"), "--bone", "nose", "--frames", "5-14",
                     "--out", str(tmp_path / "bad.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "no bone ends at" in err[0]
    assert not (tmp_path / "bad.json").exists()
