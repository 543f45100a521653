"""The skeleton-truth JSON: lossless round trip (to its printed precision) and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.errors import InputError
from core.skeleton import CLASSES
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import read_truth_json, truth_from_dict, truth_to_dict, write_truth_json


@pytest.fixture(scope="module")
def truth():
    motion = load_motion("builtin:walk", max_frames=90)
    _, t = synthesize(motion, kinds=("pan_tilt", "zoom"), noise_px=0.5, occlusion_s=0.5, seed=2)
    return t


def test_round_trip_keeps_every_field(truth, tmp_path):
    path = tmp_path / "truth.json"
    write_truth_json(truth, path)
    assert not list(tmp_path.glob("*.tmp"))
    back = read_truth_json(path)
    doc = json.loads(path.read_text())
    assert doc["format"] == "skeleton-truth" and doc["version"] == 1
    assert set(doc["proportions"]) == set(CLASSES)
    assert doc["spells"][0]["kind"] == "still" and "end" in doc["spells"][0]
    assert back.source == truth.source and back.fps == truth.fps and back.image_size == truth.image_size
    assert back.height_m == pytest.approx(truth.height_m)
    assert np.allclose(back.proportions, truth.proportions, atol=1e-10)
    assert np.allclose(back.class_lengths_m, truth.class_lengths_m, atol=1e-10)
    assert np.allclose(back.camera_position_world, truth.camera_position_world, atol=1e-8)
    assert np.allclose(back.rotation_world_from_cam0, truth.rotation_world_from_cam0, atol=1e-10)
    assert np.allclose(back.world_from_cam0, truth.world_from_cam0, atol=1e-10)
    assert [s.to_dict() for s in back.spells] == [s.to_dict() for s in truth.spells]
    assert back.occlusions == truth.occlusions and len(back.occlusions) >= 1
    assert back.generator == truth.generator
    assert back.stance == truth.stance
    assert np.array_equal(back.stance_clear, truth.stance_clear)
    assert np.array_equal(back.camera_moving, truth.camera_moving) and back.camera_moving.any()
    assert np.allclose(back.rotvec_deg, truth.rotvec_deg, atol=1e-8)
    assert np.allclose(back.focal_mm, truth.focal_mm, atol=1e-8)
    assert np.allclose(back.scale, truth.scale, atol=1e-8)
    assert np.allclose(back.joints_3d, truth.joints_3d, atol=1e-7)
    assert np.allclose(back.rotations(), truth.rotations(), atol=1e-9)


def _doc(truth):
    return json.loads(json.dumps(truth_to_dict(truth)))


@pytest.mark.parametrize("mutate,match", [
    (lambda d: d.update(format="skeleton-tracks"), "not a 'skeleton-truth'"),
    (lambda d: d.update(version=2), "version"),
    (lambda d: d.update(fps=-1), "fps"),
    (lambda d: d.update(image_size=[720]), "image_size"),
    (lambda d: d["proportions"].pop("hip"), "proportions"),
    (lambda d: d["camera"].update(rotation_world_from_cam0=[[1, 0], [0, 1]]), "rotation_world_from_cam0"),
    (lambda d: d.update(world_from_cam0=None), "world_from_cam0"),
    (lambda d: d["spells"][0].update(kind="dolly"), "spell 0"),
    (lambda d: d["frames"][3].update(stance="left"), "frame 3"),
    (lambda d: d["frames"][4].update(joints_3d=[[0, 0, 1]] * 16), "frame 4"),
    (lambda d: d["frames"][5].update(focal_mm=0), "frame 5"),
    (lambda d: d["frames"][6].update(camera_moving="yes"), "frame 6"),
    (lambda d: d.update(frames=[]), "frames"),
])
def test_bad_documents_are_one_line_input_errors(truth, mutate, match):
    doc = _doc(truth)
    mutate(doc)
    with pytest.raises(InputError, match=match) as info:
        truth_from_dict(doc, "t.json")
    assert "\n" not in str(info.value) and str(info.value).startswith("t.json: ")


def test_bad_files_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        read_truth_json(tmp_path / "missing.json")
    empty = tmp_path / "empty.json"
    empty.write_text("  \n")
    with pytest.raises(InputError, match="empty"):
        read_truth_json(empty)
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "skeleton-truth",')
    with pytest.raises(InputError, match="invalid JSON at line 1"):
        read_truth_json(broken)


def test_write_into_missing_folder_is_an_input_error(truth, tmp_path):
    with pytest.raises(InputError, match="cannot write"):
        write_truth_json(truth, tmp_path / "no" / "such" / "truth.json")
