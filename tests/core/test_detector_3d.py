"""The detector's own metric 3D joints: BlazePose's world landmarks as ``Tracks.landmarks_3d``, their place
in the ``skeleton-tracks`` file, and the bone depth order read from them.

The real-network tests run BlazePose on the test photo (tests/core/data/person_photos.npz, scikit-image's
public-domain ``astronaut``, the upper body of a woman facing the camera), as it is and after an H.264
round trip, and check what a person's 3D must be: metric bone lengths of an adult, the camera's axes
(her left shoulder on the picture's right, her head up, her face nearer the camera than her shoulders).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core.errors import InputError
from core.pose_detection.depth_cue import FARTHER, NEARER, UNKNOWN, bone_depth_order
from core.pose_detection.world_joints import world_joints
from core.skeleton import JOINT_INDEX, JOINTS, SEGMENTS
from core.tracks import Tracks, read_tracks_json, tracks_from_dict, tracks_to_dict, write_tracks_json

ROOT = Path(__file__).resolve().parents[2]
PHOTOS = ROOT / "tests" / "core" / "data" / "person_photos.npz"
J = JOINT_INDEX


def _photo(name: str = "astronaut") -> np.ndarray:
    img = np.load(PHOTOS)[name]
    return np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img


def _tracks(n=4, with_3d=True, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(100, 600, (n, 17, 2))
    pts = rng.normal(0, 0.4, (n, 17, 3)) if with_3d else None
    if with_3d:
        pts[1] = np.nan           # a frame without a person
        pts[2, J["l_wrist"]] = np.nan
    return Tracks(xy, np.ones((n, 17)), 30.0, (720, 480), landmarks_3d=pts)


# ----------------------------------------------------------------------------- mapping and axes, no network

def test_world_landmarks_become_the_canonical_joints_by_the_readers_rules():
    from core.io.formats.keypoint_sets import MEDIAPIPE_NAMES

    rng = np.random.default_rng(1)
    world = rng.normal(0, 0.3, (2, 33, 3))
    world[1] = np.nan
    out = world_joints(world)
    idx = {n: k for k, n in enumerate(MEDIAPIPE_NAMES)}
    w = world[0]
    assert out.shape == (2, 17, 3) and np.isnan(out[1]).all()
    assert np.allclose(out[0, J["l_knee"]], w[idx["left_knee"]])
    assert np.allclose(out[0, J["pelvis"]], (w[idx["left_hip"]] + w[idx["right_hip"]]) / 2)
    thorax = (w[idx["left_shoulder"]] + w[idx["right_shoulder"]]) / 2
    ears = (w[idx["left_ear"]] + w[idx["right_ear"]]) / 2
    assert np.allclose(out[0, J["spine"]], (out[0, J["pelvis"]] + thorax) / 2)
    assert np.allclose(out[0, J["head"]], 1.5 * ears - 0.5 * thorax)


def test_world_landmarks_are_turned_into_the_pictures_axes():
    from core.pose_detection.blazepose import world_in_picture_axes
    from core.pose_detection.roi import Region

    pts = np.zeros((39, 3))
    pts[0] = (0.0, -1.0, 0.25)          # "up" in the crop
    turned = world_in_picture_axes(pts, Region((0, 0), 100.0, np.pi / 2))   # the crop turned a quarter
    assert turned.shape == (33, 3)
    assert np.allclose(turned[0], (1.0, 0.0, 0.25))     # same rule as Region.to_image: up in the crop is right


# ----------------------------------------------------------------------------- Tracks and the file

def test_tracks_without_3d_landmarks_work_as_before(tmp_path):
    t = _tracks(with_3d=False)
    assert t.landmarks_3d is None
    assert "landmarks_3d" not in tracks_to_dict(t)
    write_tracks_json(t, tmp_path / "a.json")
    assert read_tracks_json(tmp_path / "a.json").landmarks_3d is None


def test_3d_landmarks_round_trip_through_the_file_and_read_any(tmp_path):
    from core.io.formats import read_any

    t = _tracks()
    path = tmp_path / "t.json"
    write_tracks_json(t, path)
    doc = json.loads(path.read_text())
    assert doc["landmarks_3d"]["joints"] == list(JOINTS) and doc["landmarks_3d"]["frames"][1] is None
    assert doc["landmarks_3d"]["frames"][2][J["l_wrist"]] is None
    for back in (read_tracks_json(path), read_any(str(path))):
        assert np.allclose(back.landmarks_3d, t.landmarks_3d, atol=5e-5, equal_nan=True)
    # any joint order, as the 2D frames
    block = doc["landmarks_3d"]
    order = list(reversed(JOINTS))
    block["frames"] = [None if row is None else [row[J[n]] for n in order] for row in block["frames"]]
    block["joints"] = order
    assert np.allclose(tracks_from_dict(doc).landmarks_3d, t.landmarks_3d, atol=5e-5, equal_nan=True)


@pytest.mark.parametrize("change,message", [
    (lambda b: b.update(joints=b["joints"][:-1]), "17 canonical joint names"),
    (lambda b: b["frames"].pop(), "one entry per frame"),
    (lambda b: b["frames"].__setitem__(0, [[0, 0]] * 17), "expected \\[x, y, z\\]"),
    (lambda b: b["frames"].__setitem__(0, [[0, 0, "x"]] * 17), "expected \\[x, y, z\\]"),
    (lambda b: b["frames"].__setitem__(0, [[0, 0, 0]] * 16), "expected 17 entries"),
])
def test_a_bad_3d_block_is_one_line(change, message):
    doc = tracks_to_dict(_tracks())
    change(doc["landmarks_3d"])
    with pytest.raises(InputError, match=message):
        tracks_from_dict(doc, "t.json")
    with pytest.raises(InputError, match="must be shaped"):
        Tracks(np.zeros((2, 17, 2)), np.ones((2, 17)), 30.0, (10, 10), landmarks_3d=np.zeros((3, 17, 3)))


def test_3d_landmarks_follow_the_frames_cut_and_the_working_rate():
    from core.timebase import to_working_rate

    t = _tracks(n=12)
    part = t.frames_between(3, 6)
    assert np.allclose(part.landmarks_3d, t.landmarks_3d[3:7], equal_nan=True)
    assert part.replaced(conf=part.conf * 0.5).landmarks_3d is part.landmarks_3d
    t = t.replaced(fps=120.0, landmarks_3d=np.broadcast_to(np.arange(12.0)[:, None, None], (12, 17, 3)).copy())
    slow = to_working_rate(t, 4)
    assert slow.landmarks_3d.shape == (3, 17, 3)
    assert np.allclose(slow.landmarks_3d[1, :, 2], 4.0)           # frame 4, averaged over 2..6


# ----------------------------------------------------------------------------- the depth order

def test_bone_depth_order_says_nearer_farther_or_unknown():
    pts = np.zeros((3, 17, 3))
    bones = [(J["l_hip"], J["l_knee"]), (J["r_hip"], J["r_knee"]), (J["l_shoulder"], J["l_elbow"])]
    pts[:, J["l_knee"]] = (0.0, 0.4, -0.2)      # leans towards the camera (z forward)
    pts[:, J["r_knee"]] = (0.0, 0.4, 0.2)       # away
    pts[:, J["l_elbow"]] = (0.3, 0.0, 0.01)     # in the picture's plane: no opinion
    pts[1, J["r_hip"]] = np.nan                 # missing
    order = bone_depth_order(pts, bones)
    assert order.dtype == np.int8 and order.shape == (3, 3)
    assert (order[:, 0] == NEARER).all() and (order[[0, 2], 1] == FARTHER).all() and order[1, 1] == UNKNOWN
    assert (order[:, 2] == UNKNOWN).all()
    assert (bone_depth_order(pts, bones, min_slant=0.0)[:, 2] == FARTHER).all()
    assert bone_depth_order(pts, SEGMENTS).shape == (3, len(SEGMENTS))
    with pytest.raises(ValueError):
        bone_depth_order(pts, [(0, 17)])


# ----------------------------------------------------------------------------- the real network

def _check_person(pts: np.ndarray, world33: np.ndarray) -> None:
    """An adult's upper body in the camera's axes, in metres.  The photo cuts her off at the elbows and
    hips, so only the bones she shows whole are held to an adult's range; the half-seen arms only to a
    loose one (measured: shoulders 0.33-0.37 m, trunk 0.46-0.47, upper arms 0.14-0.27, forearms
    0.18-0.27 on the photo and on the padded frames before and after H.264)."""
    def bone(a, b):
        return float(np.linalg.norm(pts[J[b]] - pts[J[a]]))

    # adult ranges (Drillis & Contini's fractions of a 1.5-1.9 m stature): 0.3-0.4 m between the shoulder
    # joints, 0.45-0.55 m from the hips' centre to the shoulders' (the network's scale is its own guess)
    assert 0.25 < bone("l_shoulder", "r_shoulder") < 0.45
    assert 0.35 < bone("pelvis", "thorax") < 0.6
    assert all(0.1 < bone(*b) < 0.4 for b in (("l_shoulder", "l_elbow"), ("r_shoulder", "r_elbow"),
                                              ("l_elbow", "l_wrist"), ("r_elbow", "r_wrist")))
    assert pts[J["l_shoulder"], 0] > pts[J["r_shoulder"], 0]             # x right: her left on the right
    assert pts[J["head"], 1] < pts[J["thorax"], 1] < pts[J["pelvis"], 1]  # y down
    assert world33[0, 2] < pts[J["thorax"], 2] - 0.1                      # z forward: her nose is nearer


def test_the_photo_gives_a_metric_3d_person_in_the_cameras_axes(networks):
    from core.pose_detection.detect import detect_frames

    result = detect_frames([_photo()], fps=25.0, networks=networks)
    pts = result.tracks.landmarks_3d
    assert pts is not None and pts.shape == (1, 17, 3) and np.isfinite(pts).all()
    assert np.linalg.norm(pts[0, J["pelvis"]]) < 0.05                      # origin between the hips
    _check_person(pts[0], result.world[0])


def test_a_turned_picture_turns_the_3d_joints_with_it(networks):
    from core.pose_detection.detect import detect_frames

    img = _photo()
    upright = detect_frames([img], fps=25.0, networks=networks).tracks.landmarks_3d[0]
    turned = detect_frames([np.ascontiguousarray(np.rot90(img, -1))], fps=25.0,
                           networks=networks).tracks.landmarks_3d[0]   # a quarter turn clockwise
    # in the turned picture "up" is "right"... of the picture: (x, y) -> (-y, x)
    rot = upright[:, [1, 0, 2]] * [-1, 1, 1]
    torso = [J[n] for n in ("head", "neck", "thorax", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow")]
    gap = np.linalg.norm(turned[torso] - rot[torso], axis=-1)
    assert np.median(gap) < 0.05, gap


def test_detect_on_an_h264_video_keeps_the_3d_joints_in_the_file(networks, tmp_path):
    import imageio_ffmpeg

    img = _photo()
    video = tmp_path / "clip.mp4"
    writer = imageio_ffmpeg.write_frames(str(video), (1280, 720), fps=24, macro_block_size=1)
    writer.send(None)
    for i in range(4):
        ox = 300 + 5 * i
        writer.send(np.ascontiguousarray(np.pad(img, ((100, 108), (ox, 1280 - 512 - ox), (0, 0)), mode="edge")))
    writer.close()
    out = tmp_path / "tracks.json"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-m", "core", "detect", str(video), "--out", str(out), "--quiet"],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    tracks = read_tracks_json(out)
    pts = tracks.landmarks_3d
    assert pts is not None and pts.shape == (4, 17, 3) and np.isfinite(pts).all()
    from core.pose_detection.frames import open_frames
    from core.pose_detection.tracker import PoseTracker

    for frame_pts, frame in zip(pts, open_frames(str(video)).frames(0), strict=True):   # the decoded frames
        _check_person(frame_pts, PoseTracker(networks, "per-frame").process(frame).world)
