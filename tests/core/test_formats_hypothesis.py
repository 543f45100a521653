"""Property-based tests of the track readers.

Round trips: random keypoints -> written in a format by the small writers
below (each follows the format's published layout, not the reader's code) ->
``read_any`` -> equal to the canonical joints computed here with the
documented rules, within the writer's rounding.  Garbage: random bytes, JSON
and CSV never make a reader raise anything but :class:`InputError`.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from core.errors import InputError
from core.io.formats import FORMATS, read_any, write_generic_csv
from core.skeleton import JOINTS
from core.tracks import Tracks, write_tracks_json

SIZE = (640.0, 360.0)
EXAMPLES = settings(max_examples=25)

# The formats' own keypoint orders, spelled as the detectors spell them.
BODY_25 = ("Nose", "Neck", "RShoulder", "RElbow", "RWrist", "LShoulder", "LElbow", "LWrist", "MidHip", "RHip",
           "RKnee", "RAnkle", "LHip", "LKnee", "LAnkle", "REye", "LEye", "REar", "LEar", "LBigToe", "LSmallToe",
           "LHeel", "RBigToe", "RSmallToe", "RHeel")
COCO_18 = ("Nose", "Neck", "RShoulder", "RElbow", "RWrist", "LShoulder", "LElbow", "LWrist", "RHip", "RKnee",
           "RAnkle", "LHip", "LKnee", "LAnkle", "REye", "LEye", "REar", "LEar")
COCO_17 = ("nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder", "left_elbow",
           "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee", "right_knee",
           "left_ankle", "right_ankle")
MEDIAPIPE = ("nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye",
             "right_eye_outer", "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder",
             "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky",
             "left_index", "right_index", "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee",
             "right_knee", "left_ankle", "right_ankle", "left_heel", "right_heel", "left_foot_index",
             "right_foot_index")


def canonical_name(name: str) -> str | None:
    """Detector spelling -> canonical joint (or face point); OpenPose Neck/MidHip are thorax/pelvis."""
    special = {"Neck": "thorax", "MidHip": "pelvis", "Nose": "nose", "nose": "nose"}
    if name in special:
        return special[name]
    for prefix, side in (("left_", "l_"), ("right_", "r_"), ("L", "l_"), ("R", "r_")):
        if name.startswith(prefix):
            rest = name[len(prefix):].lower()
            if rest in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle", "ear", "eye"):
                return side + rest
    return None


def expected_joints(points: dict[str, tuple[np.ndarray, np.ndarray]], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The 17 canonical joints from named points ((n, 2) xy, (n,) conf) by the rules of docs/formats.md."""
    pts = {k: (np.where((c > 0)[:, None], p, np.nan), np.where(c > 0, np.minimum(c, 1), 0.0))
           for k, (p, c) in points.items()}

    def both(a, b, fn):
        (pa, ca), (pb, cb) = pts[a], pts[b]
        ok = (ca > 0) & (cb > 0)
        return np.where(ok[:, None], fn(pa, pb), np.nan), np.where(ok, np.minimum(ca, cb), 0.0)

    def mid(a, b):
        return both(a, b, lambda p, q: (p + q) / 2)

    if "pelvis" not in pts and {"l_hip", "r_hip"} <= pts.keys():
        pts["pelvis"] = mid("l_hip", "r_hip")
    if "thorax" not in pts and {"l_shoulder", "r_shoulder"} <= pts.keys():
        pts["thorax"] = mid("l_shoulder", "r_shoulder")
    if "spine" not in pts and {"pelvis", "thorax"} <= pts.keys():
        pts["spine"] = mid("pelvis", "thorax")
    if {"l_ear", "r_ear", "thorax"} <= pts.keys():
        pts["_ears"] = mid("l_ear", "r_ear")
        if "neck" not in pts:
            pts["neck"] = mid("thorax", "_ears")
        if "head" not in pts:
            pts["_neck_rule"] = mid("thorax", "_ears")
            pts["head"] = both("_ears", "_neck_rule", lambda e, k: 2 * e - k)
    xy = np.full((n, 17, 2), np.nan)
    conf = np.zeros((n, 17))
    for j, name in enumerate(JOINTS):
        if name in pts:
            xy[:, j], conf[:, j] = pts[name]
    return xy, conf


def assert_tracks(tracks: Tracks, xy: np.ndarray, conf: np.ndarray, tol: float) -> None:
    present = conf > 0
    np.testing.assert_array_equal(tracks.present, present)
    np.testing.assert_allclose(tracks.xy[present], xy[present], atol=tol)
    np.testing.assert_allclose(tracks.conf[present], conf[present], atol=1e-9)


# --------------------------------------------------------------------------- strategies

def keypoint_array(n: int):
    """(n, 3) x, y, confidence with 0.1 px / 0.001 steps; a missing keypoint is (0, 0, 0) as detectors write it."""
    def build(ints):
        arr = np.asarray(ints, dtype=float).reshape(n, 3) * (0.1, 0.1, 0.001)
        arr[:, 2] = np.where(arr[:, 2] < 0.2, 0.0, arr[:, 2])  # about a fifth missing
        arr[arr[:, 2] == 0] = 0.0
        return arr
    return arrays(np.int64, (n * 3,), elements=st.integers(-2000, 20000)).map(
        lambda a: build(np.where(np.arange(a.size) % 3 == 2, np.abs(a) % 1001, a)))


@st.composite
def keypoint_frames(draw, n_keypoints: int, max_people: int = 1):
    """list (frames) of list (people) of (n_keypoints, 3) arrays x, y, c; missing keypoints are (0, 0, 0)."""
    n_frames = draw(st.integers(1, 4))
    frames = []
    for _ in range(n_frames):
        people = []
        for _ in range(draw(st.integers(0 if max_people > 1 else 1, max_people))):
            people.append(draw(keypoint_array(n_keypoints)))
        frames.append(people)
    return frames


def named_points(arrays: list[np.ndarray | None], names, scale=(1.0, 1.0)):
    n = len(arrays)
    out = {}
    for k, name in enumerate(names):
        canon = canonical_name(name)
        if canon is None:
            continue
        p = np.full((n, 2), np.nan)
        c = np.zeros(n)
        for f, arr in enumerate(arrays):
            if arr is not None:
                p[f] = arr[k, :2] * scale
                c[f] = arr[k, 2]
        out[canon] = (p, c)
    return out


def any_present(conf: np.ndarray) -> bool:
    return bool((conf > 0).any())


# --------------------------------------------------------------------------- round trips


@EXAMPLES
@given(layout=st.sampled_from([BODY_25, COCO_18]), data=st.data())
def test_openpose_round_trip(layout, data):
    frames = data.draw(keypoint_frames(len(layout), max_people=3))
    chosen = [max(people, key=lambda a: a[:, 2].sum()) if people else None for people in frames]
    xy, conf = expected_joints(named_points(chosen, layout), len(frames))
    with tempfile.TemporaryDirectory() as tmp:
        for f, people in enumerate(frames):
            doc = {"version": 1.3, "people": [{"person_id": [-1], "pose_keypoints_2d": a.ravel().tolist(),
                                               "hand_left_keypoints_2d": []} for a in people]}
            Path(tmp, f"clip_{f:012d}_keypoints.json").write_text(json.dumps(doc))
        if not any(people for people in frames):
            return  # covered by the "no person detected" error test
        if not any_present(conf):
            try:
                read_any(tmp, fps=30, image_size=SIZE)
            except InputError:
                return
            raise AssertionError("a clip without any joint must be refused")
        tracks = read_any(tmp, fps=30, image_size=SIZE)
    assert_tracks(tracks, xy, conf, 1e-9)


@EXAMPLES
@given(data=st.data(), results=st.booleans())
def test_coco_round_trip(data, results):
    frames = data.draw(keypoint_frames(17, max_people=2))
    if results:
        entries = []
        for f, people in enumerate(frames):
            for k, arr in enumerate(people):
                entries.append({"image_id": 5 + f, "category_id": 1, "keypoints": arr.ravel().tolist(),
                                "score": 0.5 + 0.1 * k})
        doc = entries
        chosen = [people[-1] if people else None for people in frames]  # highest score is the last
        present = [f for f, people in enumerate(frames) if people]
        if not present:
            return
        chosen = chosen[present[0]:present[-1] + 1]
    else:
        images = [{"id": 100 - f, "file_name": f"img{f}.png", "width": SIZE[0], "height": SIZE[1]}
                  for f in range(len(frames))]
        anns = []
        for f, people in enumerate(frames):
            for arr in people:
                a = arr.copy()
                a[:, 2] = np.where(a[:, 2] > 0.5, 2, np.where(a[:, 2] > 0, 1, 0))  # visibility flags
                anns.append({"image_id": 100 - f, "category_id": 1, "keypoints": a.ravel().tolist(), "iscrowd": 0})
        doc = {"images": images[::-1], "annotations": anns, "categories": [{"id": 1, "name": "person"}]}
        chosen = []
        for people in frames:
            if not people:
                chosen.append(None)
                continue
            flags = [np.where(a[:, 2] > 0.5, 1.0, np.where(a[:, 2] > 0, 0.5, 0.0)) for a in people]
            best = int(np.argmax([fl.sum() for fl in flags]))
            chosen.append(np.column_stack([people[best][:, :2], flags[best]]))
    xy, conf = expected_joints(named_points(chosen, COCO_17), len(chosen))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "kp.json")
        path.write_text(json.dumps(doc))
        if not any_present(conf):
            try:
                read_any(path, fps=30, image_size=SIZE)
            except InputError:
                return
            raise AssertionError("a clip without any joint must be refused")
        tracks = read_any(path, fps=30, image_size=None if not results else SIZE)
    assert tracks.image_size == SIZE
    assert_tracks(tracks, xy, conf, 1e-9)


@EXAMPLES
@given(data=st.data(), shape=st.sampled_from(["long", "wide", "json"]))
def test_mediapipe_round_trip(data, shape):
    n_frames = data.draw(st.integers(1, 4))
    frames = []
    landmarks = arrays(np.int64, (33, 3), elements=st.integers(0, 1200)).map(
        lambda a: (a - (100, 100, 0)) / 1000 * (1, 1, 1000 / 1200))  # x, y in -0.1..1.1, visibility 0..1
    for _ in range(n_frames):
        if data.draw(st.booleans()) or not frames:
            frames.append(data.draw(landmarks))
        else:
            frames.append(None)
    xy, conf = expected_joints(named_points(frames, MEDIAPIPE, scale=np.array(SIZE)), n_frames)
    with tempfile.TemporaryDirectory() as tmp:
        if shape == "long":
            lines = ["frame,landmark,x,y,z,visibility"]
            for f, arr in enumerate(frames):
                if arr is not None:
                    lines += [f"{f},{MEDIAPIPE[i] if f % 2 else i},{x!r},{y!r},0.0,{v!r}" for i, (x, y, v) in
                              enumerate(arr)]
            if frames[-1] is None:  # trailing empty frames cannot be represented in the long shape
                last = max(f for f, a in enumerate(frames) if a is not None)
                xy, conf = xy[:last + 1], conf[:last + 1]
            text = "\n".join(lines) + "\n"
            path = Path(tmp, "mp.csv")
        elif shape == "wide":
            header = ["frame"] + [f"{name}_{c}" for name in MEDIAPIPE for c in ("x", "y", "z", "visibility")]
            lines = [",".join(header)]
            for f, arr in enumerate(frames):
                cells = [""] * 132 if arr is None else [repr(v) for x, y, vis in arr for v in (x, y, 0.0, vis)]
                lines.append(",".join([str(f)] + cells))
            text = "\n".join(lines) + "\n"
            path = Path(tmp, "mp.csv")
        else:
            doc = [None if arr is None else {"landmarks": [{"x": x, "y": y, "z": 0.0, "visibility": v}
                                                           for x, y, v in arr]} for arr in frames]
            text = json.dumps(doc)
            path = Path(tmp, "mp.json")
        path.write_text(text)
        if not any_present(conf):
            try:
                read_any(path, fps=30, image_size=SIZE)
            except InputError:
                return
            raise AssertionError("a clip without any joint must be refused")
        tracks = read_any(path, fps=30, image_size=SIZE)
    assert_tracks(tracks, xy, conf, 1e-6)


DLC_SPELLINGS = {
    "nose": ["nose", "Nose"], "l_ear": ["LeftEar", "ear_l"], "r_ear": ["RightEar", "R_Ear"],
    "l_shoulder": ["left_shoulder", "Shoulder.L"], "r_shoulder": ["RightShoulder", "rshoulder"],
    "l_hip": ["LeftHip", "hip-left"], "r_hip": ["RightHip", "RHip"], "l_knee": ["leftknee"], "r_knee": ["KneeRight"],
    "l_ankle": ["LAnkle"], "r_ankle": ["right ankle"], "l_elbow": ["LeftElbow"], "r_elbow": ["RElbow"],
    "l_wrist": ["wrist_left"], "r_wrist": ["RIGHT_WRIST"], "neck": ["neck"], "head": ["HeadTop"],
}


@EXAMPLES
@given(data=st.data())
def test_dlc_round_trip(data):
    parts = data.draw(st.lists(st.sampled_from(sorted(DLC_SPELLINGS)), min_size=1, max_size=10, unique=True))
    names = [data.draw(st.sampled_from(DLC_SPELLINGS[p])) for p in parts]
    n = data.draw(st.integers(1, 4))
    values = {p: data.draw(keypoint_array(n)) for p in parts}
    # an undetected part is left empty (as pandas writes NaN) in even frames, written with likelihood 0 in odd ones
    blanks = {p: (values[p][:, 2] == 0) & (np.arange(n) % 2 == 0) for p in parts}
    lines = ["scorer" + ",DLC_x" * 3 * len(parts), "bodyparts" + "".join(f",{m},{m},{m}" for m in names),
             "coords" + ",x,y,likelihood" * len(parts)]
    for f in range(n):
        cells = [str(f)]
        for p in parts:
            cells += ["", "", ""] if blanks[p][f] else [repr(v) for v in values[p][f]]
        lines.append(",".join(cells))
    points = {p: (values[p][:, :2], np.where(blanks[p], 0.0, values[p][:, 2])) for p in parts}
    xy, conf = expected_joints(points, n)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "dlc.csv")
        path.write_text("\n".join(lines) + "\n")
        if not any_present(conf):
            try:
                read_any(path, fps=30, image_size=SIZE)
            except InputError:
                return
            raise AssertionError("a clip without any joint must be refused")
        tracks = read_any(path, fps=30, image_size=SIZE)
    assert_tracks(tracks, xy, conf, 1e-9)


@st.composite
def random_tracks(draw):
    n = draw(st.integers(1, 5))
    xy = draw(arrays(float, (n, 17, 2), elements=st.floats(-1e4, 1e4)))
    conf = draw(arrays(float, (n, 17), elements=st.one_of(st.just(0.0), st.floats(0.001, 1.0))))
    if not (conf > 0).any():
        conf[0, 0] = 1.0
    fps = draw(st.floats(1.0, 240.0))
    size = (float(draw(st.integers(16, 8000))), float(draw(st.integers(16, 8000))))
    return Tracks(xy, conf, fps, size, "random")


@EXAMPLES
@given(tracks=random_tracks(), fmt=st.sampled_from(["generic_csv", "native"]))
def test_canonical_formats_round_trip(tracks, fmt):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "t.csv" if fmt == "generic_csv" else "t.json")
        (write_generic_csv if fmt == "generic_csv" else write_tracks_json)(tracks, path)
        back = read_any(path)
    assert back.meta["format"] == fmt
    assert back.n_frames == tracks.n_frames and back.image_size == tracks.image_size
    assert math.isclose(back.fps, tracks.fps, rel_tol=1e-12)
    np.testing.assert_array_equal(back.present, tracks.present)
    np.testing.assert_allclose(back.xy[back.present], tracks.xy[tracks.present], atol=6e-5)
    np.testing.assert_allclose(back.conf[back.present], tracks.conf[tracks.present], atol=6e-5)


# --------------------------------------------------------------------------- garbage


def only_input_errors(path, formats) -> None:
    for fmt in formats:
        try:
            read_any(path, format=fmt, fps=30, image_size=SIZE)
        except InputError as exc:
            assert "\n" not in str(exc)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10**20, 10**20) | st.just(10**400)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.sampled_from(["nose", "left_shoulder", "person", "x", "0"]),
    lambda inner: st.lists(inner, max_size=6) | st.dictionaries(st.sampled_from(
        ["people", "pose_keypoints_2d", "keypoints", "image_id", "category_id", "score", "images", "annotations",
         "id", "file_name", "width", "height", "frames", "landmarks", "pose_landmarks", "landmark", "x", "y",
         "visibility", "frame", "fps", "image_size", "format", "version", "joints", "iscrowd", "categories", "name"]),
        inner, max_size=6),
    max_leaves=30)

JSON_FORMATS = [None, "native", "coco", "mediapipe_json"]
CSV_FORMATS = [None, "generic_csv", "dlc", "mediapipe_csv"]


@settings(max_examples=60)
@given(doc=json_values)
def test_random_json_only_input_errors(doc):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "g.json")
        path.write_text(json.dumps(doc))
        only_input_errors(path, JSON_FORMATS)
        folder = Path(tmp, "op")
        folder.mkdir()
        (folder / "a_0_keypoints.json").write_text(json.dumps(doc))
        (folder / "a_1_keypoints.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": [1.0] * 54}]}))
        only_input_errors(folder, [None, "openpose"])


landmark_like = st.one_of(
    st.fixed_dictionaries({"x": st.floats(allow_nan=True, allow_infinity=True) | st.none() | st.text(max_size=2)},
                          optional={"y": st.floats() | st.booleans(), "visibility": st.floats() | st.integers()}),
    st.none(), st.integers(), st.lists(st.floats(), max_size=3))


@settings(max_examples=40)
@given(doc=st.lists(landmark_like, min_size=32, max_size=34))
def test_random_landmark_lists_only_input_errors(doc):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "g.json")
        path.write_text(json.dumps([doc, {"landmarks": doc}]))
        only_input_errors(path, JSON_FORMATS)


cell = st.one_of(st.sampled_from(["", "nan", "inf", "-1", "0", "1", "2.5", "1e400", "x", "y", "likelihood",
                                  "scorer", "bodyparts", "coords", "individuals", "frame", "joint", "landmark",
                                  "confidence", "visibility", "nose", "l_knee", "LeftHip", "0_x", "0_y", "# fps: 3",
                                  "# frames: 9999999999", "\"", "a,b"]),
                 st.text(max_size=4))


@settings(max_examples=80)
@given(rows=st.lists(st.lists(cell, min_size=1, max_size=8), min_size=0, max_size=8))
def test_random_csv_only_input_errors(rows):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "g.csv")
        path.write_text("\n".join(",".join(r) for r in rows), encoding="utf-8")
        only_input_errors(path, CSV_FORMATS)


@settings(max_examples=100)
@given(blob=st.binary(max_size=300), ext=st.sampled_from([".json", ".csv", ".txt", ""]))
def test_random_bytes_only_input_errors(blob, ext):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, "g" + ext)
        path.write_bytes(blob)
        only_input_errors(path, [None] + [f for f, info in FORMATS.items() if not info.is_folder])
        assert os.path.exists(path)


# --------------------------------------------------------------------------- mutated sample files

DATA = Path(__file__).resolve().parent / "data" / "formats"
JSON_SAMPLES = ["native.json", "coco_results.json", "coco_annotations.json", "mediapipe.json"]
CSV_SAMPLES = ["generic.csv", "dlc.csv", "mediapipe_long.csv", "mediapipe_wide.csv"]


def _containers(doc, out):
    """Every (container, key) pair in a JSON document, to replace or delete one item."""
    items = enumerate(doc) if isinstance(doc, list) else doc.items() if isinstance(doc, dict) else ()
    for key, value in items:
        out.append((doc, key))
        _containers(value, out)
    return out


@settings(max_examples=80)
@given(name=st.sampled_from(JSON_SAMPLES), data=st.data())
def test_mutated_json_samples_only_input_errors(name, data):
    """Near-valid files (one value replaced or removed) are the likeliest bad input; they must fail cleanly."""
    doc = json.loads((DATA / name).read_text())
    slots = _containers(doc, [])
    container, key = slots[data.draw(st.integers(0, len(slots) - 1))]
    if data.draw(st.booleans()):
        container[key] = data.draw(json_values)
    elif isinstance(container, dict):
        del container[key]
    else:
        container.pop(key)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, name)
        path.write_text(json.dumps(doc))
        only_input_errors(path, JSON_FORMATS)


@settings(max_examples=120)
@given(name=st.sampled_from(CSV_SAMPLES), data=st.data())
def test_mutated_csv_samples_only_input_errors(name, data):
    rows = [line.split(",") for line in (DATA / name).read_text().splitlines()]
    r = data.draw(st.integers(0, len(rows) - 1))
    c = data.draw(st.integers(0, len(rows[r]) - 1))
    action = data.draw(st.sampled_from(["replace", "delete_cell", "delete_row", "repeat_row"]))
    if action == "replace":
        rows[r][c] = data.draw(cell)
    elif action == "delete_cell":
        del rows[r][c]
    elif action == "delete_row":
        del rows[r]
    else:
        rows.insert(r, list(rows[r]))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp, name)
        path.write_text("\n".join(",".join(row) for row in rows) + "\n")
        only_input_errors(path, CSV_FORMATS)
