"""The 2D track readers on small hand-written sample files, auto-detection, derived joints and bad input.

The samples in tests/core/data/formats are built from one standing figure
(:data:`FIGURE`, pixels in a 720x480 image) shifted 2 px right per frame, so
every expected value below is worked out from that table, not copied from a
run.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from core.errors import InputError
from core.io.formats import FORMATS, FormatInfo, detect_format_of, read_any, write_generic_csv
from core.io.formats._canonical import DERIVED, canonical_tracks
from core.io.formats.dlc import part_vocabulary
from core.skeleton import JOINT_INDEX, JOINTS
from core.tracks import Tracks, read_tracks_json

DATA = Path(__file__).resolve().parent / "data" / "formats"
SIZE = (720, 480)

FIGURE = {"nose": (360, 100), "l_eye": (366, 94), "r_eye": (354, 94), "l_ear": (374, 100), "r_ear": (346, 100),
          "l_shoulder": (390, 150), "r_shoulder": (330, 150), "l_elbow": (400, 200), "r_elbow": (320, 200),
          "l_wrist": (405, 250), "r_wrist": (315, 250), "l_hip": (380, 260), "r_hip": (340, 260),
          "l_knee": (382, 330), "r_knee": (338, 330), "l_ankle": (384, 400), "r_ankle": (336, 400)}


def at(name: str, frame: int) -> tuple[float, float]:
    x, y = FIGURE[name]
    return x + 2 * frame, y


def figure_joints(frame: int, thorax=None, pelvis=None) -> dict[str, tuple[float, float]]:
    """All 17 canonical joints of the sample figure by the documented rules (thorax/pelvis may be given)."""
    out = {j: at(j, frame) for j in JOINTS if j in FIGURE}
    mid = lambda a, b: ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)  # noqa: E731
    out["pelvis"] = pelvis or mid(out["l_hip"], out["r_hip"])
    out["thorax"] = thorax or mid(out["l_shoulder"], out["r_shoulder"])
    out["spine"] = mid(out["pelvis"], out["thorax"])
    ears = mid(at("l_ear", frame), at("r_ear", frame))
    out["neck"] = mid(out["thorax"], ears)
    out["head"] = (2 * ears[0] - out["neck"][0], 2 * ears[1] - out["neck"][1])
    return out


def assert_frame(tracks: Tracks, f: int, expected: dict, tol: float = 1e-3) -> None:
    for name, xy in expected.items():
        np.testing.assert_allclose(tracks.xy[f, JOINT_INDEX[name]], xy, atol=tol, err_msg=f"frame {f} {name}")


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def raises(match: str, path, **kwargs) -> str:
    with pytest.raises(InputError, match=match) as info:
        read_any(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert Path(path).name in message, message
    return message


# --------------------------------------------------------------------------- the registry


def test_formats_registry_describes_every_format():
    assert set(FORMATS) == {"native", "openpose", "coco", "mediapipe_csv", "mediapipe_json", "dlc", "generic_csv"}
    for name, info in FORMATS.items():
        assert isinstance(info, FormatInfo)
        assert info.label and info.description
        assert info.extensions and all(e.startswith(".") and e == e.lower() for e in info.extensions), name
        assert callable(info.reader)
    assert FORMATS["openpose"].is_folder and not any(i.is_folder for n, i in FORMATS.items() if n != "openpose")
    assert not FORMATS["native"].needs_fps and not FORMATS["native"].needs_image_size
    assert FORMATS["mediapipe_csv"].needs_image_size and FORMATS["dlc"].needs_fps


# --------------------------------------------------------------------------- each reader on its sample


def test_native_wraps_read_tracks_json_and_arguments_override():
    path = DATA / "native.json"
    base = read_tracks_json(path)
    tracks = read_any(path)
    np.testing.assert_array_equal(tracks.xy, base.xy)
    np.testing.assert_array_equal(tracks.conf, base.conf)
    assert (tracks.fps, tracks.image_size) == (30.0, (720.0, 480.0))
    assert not tracks.present[1, JOINT_INDEX["l_wrist"]]
    other = read_any(path, fps=25, image_size=(1920, 1080))
    assert (other.fps, other.image_size) == (25.0, (1920.0, 1080.0))


def test_openpose_body25_folder():
    tracks = read_any(DATA / "openpose_body25", fps=30, image_size=SIZE)
    assert tracks.n_frames == 3 and tracks.meta["layout"] == "BODY_25"
    for f in (0, 1):  # OpenPose's Neck (2 px below mid-shoulder) is the thorax, MidHip the pelvis
        assert_frame(tracks, f, figure_joints(f, thorax=(360 + 2 * f, 152), pelvis=(360 + 2 * f, 262)))
    # frame 1 holds two people; the more confident one (conf 0.8, not 0.3) is taken
    assert tracks.conf[1, JOINT_INDEX["l_knee"]] == pytest.approx(0.8)
    assert not tracks.present[2].any()  # nobody in frame 2
    assert tracks.meta["derived_joints"] == ["spine", "neck", "head"]


def test_openpose_person_index_and_coco18():
    first = read_any(DATA / "openpose_body25", format="openpose", fps=30, image_size=SIZE)
    person0 = FORMATS["openpose"].reader(str(DATA / "openpose_body25"), fps=30, image_size=SIZE, person=0)
    np.testing.assert_allclose(person0.xy[1, JOINT_INDEX["l_knee"]], at("l_knee", 50))
    np.testing.assert_allclose(person0.xy[0], first.xy[0])
    person1 = FORMATS["openpose"].reader(str(DATA / "openpose_body25"), fps=30, image_size=SIZE, person=1)
    assert not person1.present[0].any() and person1.present[1].all()
    coco18 = read_any(DATA / "openpose_coco18", fps=30, image_size=SIZE)
    assert coco18.meta["layout"] == "COCO-18" and coco18.n_frames == 2
    for f in (0, 1):
        joints = figure_joints(f, thorax=(360 + 2 * f, 152))
        assert_frame(coco18, f, joints)
    assert coco18.conf.min() == pytest.approx(0.7)


def test_coco_results_orders_by_image_id_and_fills_gaps():
    tracks = read_any(DATA / "coco_results.json", fps=30, image_size=SIZE)
    assert tracks.n_frames == 4 and tracks.meta["first_frame"] == 1  # ids 1, 2, 4: id 3 has no detection
    for f in (0, 1):
        assert_frame(tracks, f, figure_joints(f))
    assert tracks.conf[1, JOINT_INDEX["l_knee"]] == pytest.approx(0.8)  # score 0.9 beats 0.3 on image 2
    assert not tracks.present[2].any()
    assert_frame(tracks, 3, {k: v for k, v in figure_joints(3).items() if k not in ("neck", "head")})
    assert not tracks.present[3, JOINT_INDEX["head"]] and not tracks.present[3, JOINT_INDEX["neck"]]  # no l_ear
    raises("COCO keypoints JSON has no image size; pass image_size=", DATA / "coco_results.json", fps=30)


def test_coco_annotations_order_by_file_name_and_take_image_size():
    tracks = read_any(DATA / "coco_annotations.json", fps=30)
    assert tracks.image_size == (720.0, 480.0)
    assert tracks.n_frames == 3  # clip_1, clip_2, clip_10 although ids are 3, 7, 10 listed backwards
    for f in (0, 1):
        assert_frame(tracks, f, figure_joints(f))
    assert tracks.conf[0, JOINT_INDEX["l_knee"]] == 1.0  # visibility 2
    assert tracks.conf[1, JOINT_INDEX["l_knee"]] == 0.5  # visibility 1 (labelled, occluded)
    assert not tracks.present[2, JOINT_INDEX["pelvis"]] and not tracks.present[2, JOINT_INDEX["spine"]]
    assert tracks.present[2, JOINT_INDEX["thorax"]]


def test_coco_entry_without_score_and_real_confidences(tmp_path):
    entry = _coco_entry(1, score=None)
    del entry["score"]
    entry["keypoints"][2::3] = [0.7] * 17  # a detector's confidences, not visibility flags
    tracks = read_any(write(tmp_path / "noscore.json", json.dumps([entry])), fps=30, image_size=SIZE)
    assert tracks.conf[0, JOINT_INDEX["l_knee"]] == pytest.approx(0.7)


@pytest.mark.parametrize("name", ["mediapipe_long.csv", "mediapipe_wide.csv", "mediapipe.json"])
def test_mediapipe_normalised_to_pixels(name):
    kwargs = {"image_size": SIZE, "fps": 30} if name.endswith(".csv") else {}
    tracks = read_any(DATA / name, **kwargs)
    assert tracks.image_size == (720.0, 480.0)
    frames = {"mediapipe_long.csv": [0, 1, None, 3], "mediapipe_wide.csv": [0, None, 2],
              "mediapipe.json": [0, 1, None]}[name]
    assert tracks.n_frames == len(frames)
    for f, shift in enumerate(frames):
        if shift is None:
            assert not tracks.present[f].any()
        else:
            assert_frame(tracks, f, figure_joints(shift), tol=1e-3)
    # visibility is 0.5 + index / 100: left knee is landmark 25, nose 0, ears 7 and 8
    assert tracks.conf[0, JOINT_INDEX["l_knee"]] == pytest.approx(0.75)
    assert tracks.conf[0, JOINT_INDEX["head"]] == pytest.approx(0.57)  # min(ears 0.57, 0.58, shoulders 0.61..)
    if name == "mediapipe.json":
        assert tracks.fps == 25.0


def test_mediapipe_wide_without_frame_column_keeps_empty_rows(tmp_path):
    header = ",".join(f"x{i},y{i},v{i}" for i in range(33))
    row = ",".join(f"{0.1 + i / 100},{0.2 + i / 100},0.9" for i in range(33))
    path = write(tmp_path / "wide.csv", f"{header}\n{row}\n{',' * 98}\n{row}\n")
    tracks = read_any(path, fps=30, image_size=(1000, 500))
    assert tracks.n_frames == 3 and not tracks.present[1].any()
    l_hip = (0.1 + 23 / 100, 0.2 + 23 / 100)  # landmark 23 = left_hip
    np.testing.assert_allclose(tracks.xy[2, JOINT_INDEX["l_hip"]], (l_hip[0] * 1000, l_hip[1] * 500))


def test_mediapipe_needs_image_size_message():
    message = raises("MediaPipe CSV has no image size; pass image_size=\\(w, h\\)", DATA / "mediapipe_long.csv",
                     fps=30)
    assert message.startswith(str(DATA / "mediapipe_long.csv"))
    raises("has no frame rate; pass fps=", DATA / "mediapipe_wide.csv", image_size=SIZE)


def test_dlc_maps_body_part_names():
    tracks = read_any(DATA / "dlc.csv", fps=30, image_size=SIZE)
    assert tracks.meta["ignored_parts"] == ["tailbase"]
    for f in range(3):
        expected = figure_joints(f)
        if f == 1:  # LeftEar cells empty in frame 1: neck and head cannot be derived
            expected = {k: v for k, v in expected.items() if k not in ("neck", "head")}
            assert not tracks.present[1, JOINT_INDEX["neck"]] and not tracks.present[1, JOINT_INDEX["head"]]
        assert_frame(tracks, f, expected)
    assert tracks.conf[0, JOINT_INDEX["head"]] == pytest.approx(0.6)  # ear_right has likelihood 0.6
    assert tracks.conf[0, JOINT_INDEX["spine"]] == pytest.approx(0.9)


@pytest.mark.parametrize("name, expected", [
    ("LeftShoulder", "l_shoulder"), ("shoulder_l", "l_shoulder"), ("Shoulder.R", "r_shoulder"),
    ("right-knee", "r_knee"), ("R_ANKLE", "r_ankle"), ("Nose", "nose"), ("head_top", "head"),
    ("mid hip", "pelvis"), ("Neck", "neck"), ("tailbase", None), ("shoulder", None),
])
def test_dlc_name_table(name, expected):
    assert part_vocabulary(name) == expected


def test_generic_csv_reads_settings_and_does_not_derive():
    tracks = read_any(DATA / "generic.csv")
    assert (tracks.fps, tracks.image_size, tracks.n_frames) == (24.0, (720.0, 480.0), 2)
    np.testing.assert_allclose(tracks.xy[1, JOINT_INDEX["l_hip"]], at("l_hip", 1))
    np.testing.assert_allclose(tracks.xy[0, JOINT_INDEX["pelvis"]], at("nose", 0))  # given, not mid-hip
    assert not tracks.present[:, JOINT_INDEX["spine"]].any()
    assert tracks.present.sum() == 8 and np.all(tracks.conf[tracks.present] == 0.75)


def test_generic_csv_writer_round_trip(tmp_path):
    tracks = read_any(DATA / "dlc.csv", fps=29.97, image_size=SIZE)
    write_generic_csv(tracks, tmp_path / "out.csv")
    back = read_any(tmp_path / "out.csv")
    assert (back.fps, back.image_size, back.n_frames) == (29.97, tracks.image_size, tracks.n_frames)
    np.testing.assert_array_equal(back.present, tracks.present)
    np.testing.assert_allclose(back.xy[back.present], tracks.xy[tracks.present], atol=1e-4)


# --------------------------------------------------------------------------- auto-detection


@pytest.mark.parametrize("name, fmt", [
    ("native.json", "native"), ("openpose_body25", "openpose"), ("openpose_coco18", "openpose"),
    ("coco_results.json", "coco"), ("coco_annotations.json", "coco"), ("mediapipe_long.csv", "mediapipe_csv"),
    ("mediapipe_wide.csv", "mediapipe_csv"), ("mediapipe.json", "mediapipe_json"), ("dlc.csv", "dlc"),
    ("generic.csv", "generic_csv"),
])
def test_auto_detection(name, fmt):
    assert detect_format_of(DATA / name) == fmt
    detected = read_any(DATA / name, fps=30, image_size=SIZE)
    named = read_any(DATA / name, format=fmt, fps=30, image_size=SIZE)
    np.testing.assert_array_equal(detected.xy, named.xy)
    assert detected.meta["format"] == fmt


def test_auto_detection_refuses_unknown_content(tmp_path):
    raises("cannot tell the file format; pass format= one of", write(tmp_path / "x.json", '{"hello": 1}'))
    raises("cannot tell the file format", write(tmp_path / "x.csv", "a,b,c\n1,2,3\n"))
    raises("cannot tell the file format", write(tmp_path / "x.bvh", "HIERARCHY\n"))
    # damaged files are still sent to the reader that can say what is wrong with them
    damaged_native = {"format": "skeleton-track", "joints": list(JOINTS), "frames": []}
    raises("not a 'skeleton-tracks' file", write(tmp_path / "n.json", json.dumps(damaged_native)))
    damaged_coco = [{"keypoints": [0] * 51}]
    raises(r"entry 0: \"image_id\" must be", write(tmp_path / "c.json", json.dumps(damaged_coco)), fps=30,
           image_size=SIZE)
    raises("one OpenPose frame; pass the folder",
           shutil.copy(DATA / "openpose_coco18" / "0_keypoints.json", tmp_path / "0_keypoints.json"))


# --------------------------------------------------------------------------- derived joints


def test_derived_joints_follow_the_documented_rules():
    rng = np.random.default_rng(3)
    names = ["l_hip", "r_hip", "l_shoulder", "r_shoulder", "l_ear", "r_ear"]
    xy = rng.uniform(0, 500, (6, len(names), 2))
    conf = rng.uniform(0.1, 1.0, (6, len(names)))
    conf[2, 0] = 0.0  # left hip missing in frame 2
    conf[4, 5] = 0.0  # right ear missing in frame 4
    t = canonical_tracks(xy, conf, names, fps=30, image_size=SIZE, source="mem")
    p = {n: xy[:, k] for k, n in enumerate(names)}
    c = {n: conf[:, k] for k, n in enumerate(names)}
    pelvis = (p["l_hip"] + p["r_hip"]) / 2
    thorax = (p["l_shoulder"] + p["r_shoulder"]) / 2
    ears = (p["l_ear"] + p["r_ear"]) / 2
    neck = (thorax + ears) / 2
    expected = {"pelvis": pelvis, "thorax": thorax, "spine": (pelvis + thorax) / 2, "neck": neck,
                "head": ears + (ears - neck)}
    ok = {"pelvis": [0, 1, 3, 4, 5], "spine": [0, 1, 3, 4, 5], "thorax": list(range(6)),
          "neck": [0, 1, 2, 3, 5], "head": [0, 1, 2, 3, 5]}
    for joint, pos in expected.items():
        j = JOINT_INDEX[joint]
        np.testing.assert_allclose(t.xy[ok[joint], j], pos[ok[joint]], atol=1e-9)
        assert not t.present[[f for f in range(6) if f not in ok[joint]], j].any()
    np.testing.assert_allclose(t.conf[:, JOINT_INDEX["spine"]],
                               np.where(conf[:, 0] > 0, np.min([c[n] for n in names[:4]], axis=0), 0))
    np.testing.assert_allclose(t.conf[[0, 1], JOINT_INDEX["head"]],
                               np.min([c[n] for n in names[2:]], axis=0)[[0, 1]])
    assert t.meta["derived_joints"] == list(DERIVED)
    # knees, ankles, elbows, wrists were not given: absent, never invented
    assert set(t.meta["unavailable_joints"]) == {"l_knee", "r_knee", "l_ankle", "r_ankle", "l_elbow", "r_elbow",
                                                  "l_wrist", "r_wrist"}


def test_given_joints_are_not_overwritten_by_rules():
    xy = np.array([[[10.0, 10.0], [0.0, 0.0], [4.0, 0.0]]])
    t = canonical_tracks(xy, np.ones((1, 3)), ["pelvis", "l_hip", "r_hip"], fps=30, image_size=SIZE, source="m")
    np.testing.assert_allclose(t.xy[0, JOINT_INDEX["pelvis"]], (10, 10))


def test_min_confidence_drops_low_joints_and_derived_ones_with_them():
    tracks = read_any(DATA / "dlc.csv", fps=30, image_size=SIZE, min_confidence=0.7)
    assert not tracks.present[:, JOINT_INDEX["head"]].any()  # r_ear 0.6 < 0.7
    assert tracks.present[:, JOINT_INDEX["spine"]].all()
    raises("no joint reaches min_confidence=0.95", DATA / "dlc.csv", fps=30, image_size=SIZE, min_confidence=0.95)


# --------------------------------------------------------------------------- bad input

GENERIC_HEAD = "# fps: 30\n# image_size: 720 480\nframe,joint,x,y,confidence\n"


@pytest.mark.parametrize("body, match", [
    (GENERIC_HEAD + "0,left_knee,1,2,1\n", r"line 4: unknown joint 'left_knee'"),
    (GENERIC_HEAD + "0,l_knee,nan,2,1\n", r"line 4: x 'nan' is not a finite number"),
    (GENERIC_HEAD + "0,l_knee,1,inf,1\n", r"line 4: y 'inf' is not a finite number"),
    (GENERIC_HEAD + "0,l_knee,1,2\n", r"line 4: 4 cells but the header has 5"),
    (GENERIC_HEAD + "0,l_knee,1,2,1\n0,l_knee,3,4,1\n", r"line 5: joint 'l_knee' listed twice in frame 0"),
    (GENERIC_HEAD + "0,l_knee,1,2,-0.5\n", r"line 4: negative confidence"),
    (GENERIC_HEAD + "zero,l_knee,1,2,1\n", r"line 4: frame 'zero' is not an integer"),
    (GENERIC_HEAD + "0,l_knee,1,2,0\n", r"every joint has confidence 0"),
    (GENERIC_HEAD, r"header only; no frames"),
    ("frame,joint,x\n0,l_knee,1\n", r"line 1: missing columns \['y'\]"),
    ("frame,joint,x,y,confidnce\n0,l_knee,1,2,1\n", r"unknown columns \['confidnce'\]"),
    ("# fps: -30\nframe,joint,x,y\n0,l_knee,1,2\n", r"line 1: '# fps:' needs one positive number"),
    ("# fps: 0\nframe,joint,x,y\n0,l_knee,1,2\n", r"line 1: '# fps:' needs one positive number"),
    ("", r"file is empty"),
    ("  \n\n", r"file is empty"),
])
def test_generic_csv_bad_input(tmp_path, body, match):
    raises(match, write(tmp_path / "bad.csv", body), format="generic_csv")


def test_generic_csv_needs_fps_and_image_size(tmp_path):
    path = write(tmp_path / "plain.csv", "frame,joint,x,y\n0,l_knee,1,2\n")
    raises("generic CSV has no frame rate; pass fps=", path, image_size=SIZE)
    raises("generic CSV has no image size; pass image_size=", path, fps=30)
    assert read_any(path, fps=30, image_size=SIZE).n_frames == 1


@pytest.mark.parametrize("kwargs, match", [
    ({"fps": -1}, "fps must be a positive number, got -1"),
    ({"fps": 0}, "fps must be a positive number, got 0"),
    ({"fps": float("nan")}, "fps must be a positive number"),
    ({"image_size": (720, 0)}, r"image_size must be \(width, height\)"),
    ({"image_size": (720,)}, r"image_size must be \(width, height\)"),
    ({"min_confidence": 1.5}, "min_confidence must be a number in 0..1"),
    ({"format": "bvh"}, "unknown format 'bvh'; choose one of"),
])
def test_bad_arguments(kwargs, match):
    raises(match, DATA / "native.json", **kwargs)


def test_undecodable_and_broken_files(tmp_path):
    (tmp_path / "latin1.csv").write_bytes("frame,joint,x,y\n0,l_knee,1,2 \xe9\n".encode("latin-1"))
    raises("not a UTF-8 text file", tmp_path / "latin1.csv", format="generic_csv", fps=30, image_size=SIZE)
    raises("invalid JSON at line 2, column 1", write(tmp_path / "cut.json", '[{"image_id": 1,\n'), format="coco")
    quote = write(tmp_path / "quote.csv", 'frame,joint,x,y\n0,"l_knee\n')  # unterminated quote eats the line
    raises("line 2: 2 cells but the header has 4", quote, format="generic_csv", fps=30, image_size=SIZE)


def test_openpose_ignores_other_json_beside_keypoint_files(tmp_path):
    folder = tmp_path / "op"
    shutil.copytree(DATA / "openpose_coco18", folder)
    write(folder / "settings.json", '{"net_resolution": "-1x368"}')
    assert read_any(folder, fps=30, image_size=SIZE).n_frames == 2


def test_bad_paths(tmp_path):
    raises("no such file or folder", tmp_path / "nothing.json")
    raises("no such file", tmp_path / "nothing.csv", format="dlc")
    raises("expects a folder, not a file", DATA / "dlc.csv", format="openpose")
    raises("expects a file, not a folder", DATA / "openpose_coco18", format="coco")


def test_native_bad_input(tmp_path):
    doc = json.loads((DATA / "native.json").read_text())
    raises('"fps" must be a positive number, got -5', write(tmp_path / "neg.json", json.dumps({**doc, "fps": -5})))
    ragged = {**doc, "frames": [doc["frames"][0], doc["frames"][1][:-1]]}
    raises("frame 1: expected 17 joint entries, got 16", write(tmp_path / "ragged.json", json.dumps(ragged)))
    wrong = {**doc, "joints": ["hips"] + doc["joints"][1:]}
    raises(r"unknown joint name\(s\) \['hips'\]", write(tmp_path / "names.json", json.dumps(wrong)))
    nan = json.dumps(doc).replace("[300, 100, 0.9]", "[NaN, 100, 0.9]", 1)
    raises("frame 0, joint 'head': non-finite value", write(tmp_path / "nan.json", nan))
    raises("file is empty", write(tmp_path / "empty.json", ""), format="native")


def _openpose_frame(n_numbers: int, value=100.0, conf=0.9) -> str:
    kp = [value if i % 3 < 2 else conf for i in range(n_numbers)]
    return json.dumps({"version": 1.3, "people": [{"pose_keypoints_2d": kp}]})


def test_openpose_bad_input(tmp_path):
    def folder(name, files: dict[str, str]) -> Path:
        d = tmp_path / name
        d.mkdir()
        for fname, text in files.items():
            (d / fname).write_text(text)
        return d

    ok = {"fps": 30, "image_size": SIZE}
    raises("no .json files in this folder", folder("empty", {"notes.txt": "x"}), **ok)
    raises(r"a_000000000001_keypoints.json: person 0 has 60 numbers in pose_keypoints_2d; expected 75",
           folder("ragged", {"a_000000000000_keypoints.json": _openpose_frame(75),
                             "a_000000000001_keypoints.json": _openpose_frame(60)}), **ok)
    message = raises(r"COCO-18 keypoints, but a_000000000000_keypoints.json has BODY_25; all files must use one",
                     folder("mixed", {"a_000000000000_keypoints.json": _openpose_frame(75),
                                      "a_000000000001_keypoints.json": _openpose_frame(54)}), **ok)
    assert "a_000000000001_keypoints.json" in message
    raises(r"b_000000000000_keypoints.json: person 0, keypoint 0: nan is not a finite number",
           folder("nan", {"b_000000000000_keypoints.json": _openpose_frame(54, value=float("nan"))}), **ok)
    raises("negative confidence",
           folder("negconf", {"b_000000000000_keypoints.json": _openpose_frame(54, conf=-1)}), **ok)
    raises("files of several sequences are mixed here",
           folder("two", {"a_0_keypoints.json": _openpose_frame(54), "b_0_keypoints.json": _openpose_frame(54)}),
           **ok)
    raises("no person detected in any of the 2 frame files",
           folder("nobody", {"c_0.json": '{"people": []}', "c_1.json": '{"people": []}'}), **ok)
    raises(r"c_0.json: not an OpenPose frame", folder("notop", {"c_0.json": "[1, 2]"}), **ok)
    raises(r"c_0.json: invalid JSON at line 1", folder("broken", {"c_0.json": '{"people": [}'}), **ok)
    raises("OpenPose JSON folder has no frame rate; pass fps=", DATA / "openpose_coco18", image_size=SIZE)
    raises(r"OpenPose JSON folder has no image size; pass image_size=\(w, h\)", DATA / "openpose_coco18", fps=30)


def _coco_entry(image_id, n=51, value=10.0, score=0.9):
    return {"image_id": image_id, "category_id": 1, "keypoints": [value if i % 3 < 2 else 1 for i in range(n)],
            "score": score}


def test_coco_bad_input(tmp_path):
    ann = json.loads((DATA / "coco_annotations.json").read_text())
    ann["images"][1]["width"] = 1280
    message = raises("mixed image sizes", write(tmp_path / "sizes.json", json.dumps(ann)), fps=30)
    assert "720x480" in message and "1280x480" in message
    raises(r"entry 1 \(image 2\): \"keypoints\" must hold 51 numbers \(17 x \[x, y, v\]\), got 48",
           write(tmp_path / "short.json", json.dumps([_coco_entry(1), _coco_entry(2, n=48)])), fps=30,
           image_size=SIZE)
    raises(r"entry 0 \(image 1\), keypoint nose: nan is not a finite number",
           write(tmp_path / "nan.json", json.dumps([_coco_entry(1, value=float("nan"))])), fps=30, image_size=SIZE)
    raises("no person keypoints in this COCO results file",
           write(tmp_path / "cats.json", json.dumps([{**_coco_entry(1), "category_id": 2}])), format="coco",
           fps=30, image_size=SIZE)
    ann = json.loads((DATA / "coco_annotations.json").read_text())
    ann["annotations"][0]["image_id"] = 99
    raises("annotation for image id 99, which is not in \"images\"", write(tmp_path / "ids.json", json.dumps(ann)),
           fps=30)
    ann["categories"] = 5  # not a list: the person category falls back to id 1
    ann["annotations"][0]["image_id"] = 3
    assert read_any(write(tmp_path / "cat.json", json.dumps(ann)), fps=30).present[0].all()
    raises("image ids too large to be frame numbers",
           write(tmp_path / "huge.json", json.dumps([_coco_entry(10**20)])), fps=30, image_size=SIZE)
    ann["images"] = []
    raises("\"images\" is empty; no frames", write(tmp_path / "noimg.json", json.dumps(ann)), fps=30)
    raises("image ids mix numbers and strings",
           write(tmp_path / "mixids.json", json.dumps([_coco_entry(1), _coco_entry("b")])), fps=30, image_size=SIZE)
    raises("image ids run from 1 to 10000000 but only 2 are present",
           write(tmp_path / "sparse.json", json.dumps([_coco_entry(1), _coco_entry(10_000_000)])), fps=30,
           image_size=SIZE)


def _mediapipe_long(frames: dict[int, int]) -> str:
    lines = ["frame,landmark,x,y,visibility"]
    for f, count in frames.items():
        lines += [f"{f},{i},0.5,0.5,0.9" for i in range(count)]
    return "\n".join(lines) + "\n"


def test_mediapipe_bad_input(tmp_path):
    ok = {"fps": 30, "image_size": SIZE}
    raises(r"frame 1 \(ending line 66\) has 32 landmarks; MediaPipe Pose frames have all 33",
           write(tmp_path / "ragged.csv", _mediapipe_long({0: 33, 1: 32})), **ok)
    raises("line 2: unknown landmark 'left_toe'",
           write(tmp_path / "names.csv", "frame,landmark,x,y\n0,left_toe,0.1,0.2\n"), **ok)
    raises("line 2: x 'NaN' is not a finite number",
           write(tmp_path / "nan.csv", "frame,landmark,x,y\n0,nose,NaN,0.2\n"), **ok)
    header = ",".join(f"{i}_{c}" for i in range(33) for c in ("x", "y"))
    raises(r"missing columns \['32_x', '32_y'\]", write(tmp_path / "cols.csv", header.rsplit(",", 2)[0] + "\n" +
                                                        ",".join(["0.5"] * 64) + "\n"), format="mediapipe_csv", **ok)
    raises("line 2: some landmark cells are empty",
           write(tmp_path / "part.csv", header + "\n" + ",".join(["0.5"] * 65) + ",\n"), **ok)
    landmarks = [{"x": 0.5, "y": 0.5}] * 32
    raises("frame 1: expected 33 landmarks, got 32",
           write(tmp_path / "ragged.json", json.dumps([[{"x": 0.1, "y": 0.1}] * 33, landmarks])), **ok)
    raises(r"frame 0, landmark 3: x=nan is not a finite number",
           write(tmp_path / "nan.json", json.dumps([[{"x": 0.1, "y": 0.1}] * 3 + [{"x": math.nan, "y": 0}] * 30])),
           **ok)
    raises("no frames", write(tmp_path / "none.json", json.dumps({"frames": []})), format="mediapipe_json", **ok)
    raises("\"fps\" must be|fps must be a positive number",
           write(tmp_path / "fps.json", json.dumps({"fps": -2, "frames": [[{"x": 0.1, "y": 0.1}] * 33]})),
           image_size=SIZE)
    raises("MediaPipe JSON has no image size; pass image_size=",
           write(tmp_path / "nosize.json", json.dumps([[{"x": 0.1, "y": 0.1}] * 33])), fps=30)


DLC_HEAD = ("scorer,s,s,s,s,s,s\nbodyparts,nose,nose,nose,leftear,leftear,leftear\n"
            "coords,x,y,likelihood,x,y,likelihood\n")


@pytest.mark.parametrize("body, match", [
    (DLC_HEAD + "0,1,2,0.9,3,4\n", r"line 4: 6 cells but the header has 7"),
    (DLC_HEAD + "0,1,2,0.9,nan,4,0.9\n", r"line 4: body part 'leftear' x 'nan' is not a finite number"),
    (DLC_HEAD + "0,1,2,-0.9,3,4,0.9\n", r"line 4: body part 'nose' has a negative likelihood"),
    (DLC_HEAD, r"no frames after the header"),
    (DLC_HEAD.replace("nose,nose,nose,leftear,leftear,leftear", "a,a,a,b,b,b") + "0,1,2,1,3,4,1\n",
     r"no body part name is recognised \(\['a', 'b'\]\)"),
    (DLC_HEAD.replace("coords,x,y,likelihood,x,y", "coords,x,z,likelihood,x,y") + "0,1,2,1,3,4,1\n",
     r"missing columns: body part 'nose' needs both x and y"),
    ("scorer,s,s\ncoords,x,y\n0,1,2\n", r"line 2: expected the 'bodyparts' header row"),
    (DLC_HEAD.replace("leftear,leftear,leftear", "Nose,Nose,Nose") + "0,1,2,1,3,4,1\n",
     r"body parts 'nose' and 'Nose' both mean nose"),
])
def test_dlc_bad_input(tmp_path, body, match):
    raises(match, write(tmp_path / "bad.csv", body), fps=30, image_size=SIZE)


def test_dlc_multi_animal_takes_the_most_confident_individual(tmp_path):
    text = ("scorer,s,s,s,s,s,s\nindividuals,ann,ann,ann,bob,bob,bob\nbodyparts,lhip,lhip,lhip,lhip,lhip,lhip\n"
            "coords,x,y,likelihood,x,y,likelihood\n0,1,2,0.2,5,6,0.8\n1,1,2,0.3,,,\n")
    tracks = read_any(write(tmp_path / "ma.csv", text), fps=30, image_size=SIZE)
    assert tracks.meta["individual"] == "bob"
    np.testing.assert_allclose(tracks.xy[0, JOINT_INDEX["l_hip"]], (5, 6))
    assert not tracks.present[1].any()


def test_natural_order_of_frame_files():
    from core.io.formats._io import natural_key

    names = ["f_10.json", "f_2.json", "f_1.json", "f_" + "9" * 5000 + ".json", "f_0100.json"]
    assert [n[:8] for n in sorted(names, key=natural_key)] == ["f_1.json", "f_2.json", "f_10.jso", "f_0100.j",
                                                               "f_999999"]
