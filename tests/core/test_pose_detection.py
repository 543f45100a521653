"""The offline pose detector (core/pose_detection): geometry, decoding, frames, and BlazePose on real photos.

The photos (tests/core/data/person_photos.npz, from scikit-image's data: ``astronaut``, NASA, public
domain; ``camera``, CC0 by Lav Varshney; docs/pose_detection.md) are real people.  The expected
positions are MediaPipe 0.10.14's own BlazePose run on the same images (``mp.solutions.pose``, full
model, static image mode), rounded; our numpy decoding must land within 10 px of them.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core.errors import InputError
from core.pose_detection import blazepose, frames, runtime
from core.pose_detection.region_filter import AlignmentFilter
from core.pose_detection.roi import Region, crop, region_from_alignment, tiles, whole_frame

ROOT = Path(__file__).resolve().parents[2]
PHOTOS = ROOT / "tests" / "core" / "data" / "person_photos.npz"

#: MediaPipe's BlazePose on the photos: landmark index -> (x, y) px, for landmarks it saw (visibility >= 0.97)
REFERENCE = {
    "astronaut": {0: (222.7, 128.0), 2: (248.9, 112.5), 5: (205.0, 103.3), 7: (268.0, 122.8), 8: (190.4, 107.4),
                  11: (306.2, 256.6), 12: (112.7, 240.0)},
    "camera": {0: (247.0, 169.6), 2: (250.8, 152.4), 5: (236.6, 151.7), 7: (231.0, 144.0), 8: (203.3, 143.4),
               11: (219.6, 169.1), 12: (104.7, 181.8), 14: (142.5, 302.3)},
}


def _photo(name: str) -> np.ndarray:
    img = np.load(PHOTOS)[name]
    return np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img


# ----------------------------------------------------------------------------- geometry, no networks

def test_anchors_follow_the_ssd_layout():
    a = blazepose.ANCHORS
    assert a.shape == (2254, 2)
    assert np.allclose(a[0], [0.5 / 28, 0.5 / 28]) and np.allclose(a[1], a[0])   # two per cell
    assert np.allclose(a[2], [1.5 / 28, 0.5 / 28])                                # x runs fastest
    assert np.allclose(a[1568], [0.5 / 14, 0.5 / 14])                             # stride 16 after 28*28*2
    assert np.allclose(a[-6:], [6.5 / 7, 6.5 / 7])                                # strides 32 x3: six per cell


@pytest.mark.parametrize("direction", [(0.0, -1.0), (1.0, 0.0), (-0.6, 0.8), (0.3, -0.95)])
def test_alignment_region_puts_the_scale_point_straight_above_the_centre(direction):
    centre = np.array([400.0, 300.0])
    d = 120.0
    scale_point = centre + d * np.array(direction) / np.hypot(*direction)
    r = region_from_alignment(centre, scale_point)
    assert r.side == pytest.approx(2 * d * 1.25)
    assert np.allclose(r.to_image(np.array([0.5, 0.5])), centre)
    assert np.allclose(r.to_image(np.array([0.5, 0.5 - 1 / 2.5])), scale_point)  # top centre of the crop
    if direction == (0.0, -1.0):
        assert r.rotation == pytest.approx(0.0)


def test_crop_of_the_whole_square_frame_is_the_frame():
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, size=(64, 64, 3), dtype=np.uint8)
    out = crop(img, whole_frame(64, 64), 64, replicate=False)
    assert np.array_equal(out, img.astype(np.float32))


def test_crop_of_a_translated_image_is_translation_equivariant():
    rng = np.random.default_rng(1)
    img = rng.integers(0, 256, size=(80, 100, 3), dtype=np.uint8)
    r = Region((50.3, 40.7), 31.0, 0.4)
    shifted = np.pad(img, ((7, 0), (5, 0), (0, 0)), mode="edge")
    a = crop(img, r, 24, replicate=True)
    b = crop(shifted, Region((55.3, 47.7), 31.0, 0.4), 24, replicate=True)
    assert np.allclose(a, b, atol=1e-3)


def test_detections_decode_to_image_pixels_through_the_letterbox():
    raw = np.zeros((2254, 12))
    scores = np.full((2254, 1), -20.0)
    k = 1568 + 2 * (14 * 5 + 9)        # a stride-16 anchor, row 5, column 9
    raw[k, 2:4] = 40.0                   # box 40 x 40 input px
    raw[k, 4:6] = (0.0, 30.0)            # keypoint 0: 30 input px below the anchor
    raw[k, 6:8] = (0.0, -50.0)           # keypoint 1: 50 px above
    scores[k] = 6.0
    frame = whole_frame(448, 224)        # landscape: letterboxed to a 448 x 448 square
    found = blazepose.decode_detections(raw, scores, frame)
    assert len(found) == 1
    anchor = blazepose.ANCHORS[k]
    expect0 = (anchor + [0.0, 30.0 / 224]) * 448 - [0.0, 112.0]   # square -> frame: 112 px of padding above
    assert np.allclose(found[0].keypoints[0], expect0)
    assert found[0].score == pytest.approx(1 / (1 + math.exp(-6.0)))
    region = found[0].region()
    assert region.rotation == pytest.approx(0.0) and region.side == pytest.approx(2 * 80 * 2 * 1.25)


def test_overlapping_detections_merge_and_distinct_ones_stay():
    raw = np.zeros((2254, 12))
    scores = np.full((2254, 1), -20.0)
    raw[:, 2:4] = 60.0
    scores[100], scores[102] = 4.0, 3.0   # neighbouring cells: the same person
    scores[1500] = 2.0                    # far away: another
    found = blazepose.decode_detections(raw, scores, whole_frame(224, 224))
    assert len(found) == 2 and found[0].score > found[1].score


def _write_bmp(path, img, bpp, top_down):
    h, w = img.shape[:2]
    channels = bpp // 8
    px = img[..., ::-1]
    if channels == 4:
        px = np.concatenate([px, np.full((h, w, 1), 255, np.uint8)], axis=2)
    stride = (w * channels + 3) // 4 * 4
    rows = np.zeros((h, stride), np.uint8)
    rows[:, :w * channels] = px.reshape(h, -1)
    if not top_down:
        rows = rows[::-1]
    header = bytearray(54)
    header[0:2] = b"BM"
    header[10:14] = (54).to_bytes(4, "little")
    header[14:18] = (40).to_bytes(4, "little")
    header[18:22] = w.to_bytes(4, "little", signed=True)
    header[22:26] = (-h if top_down else h).to_bytes(4, "little", signed=True)
    header[26:28] = (1).to_bytes(2, "little")
    header[28:30] = bpp.to_bytes(2, "little")
    Path(path).write_bytes(bytes(header) + rows.tobytes())


@pytest.mark.parametrize("bpp,top_down", [(24, False), (32, True), (24, True)])
def test_bmp_reader_round_trip(tmp_path, bpp, top_down):
    rng = np.random.default_rng(2)
    img = rng.integers(0, 256, size=(7, 13, 3), dtype=np.uint8)   # odd width: padded rows
    _write_bmp(tmp_path / "f.bmp", img, bpp, top_down)
    assert np.array_equal(frames.read_bmp(str(tmp_path / "f.bmp")), img)


def test_bad_frame_files_get_one_line(tmp_path):
    (tmp_path / "x.bmp").write_bytes(b"not an image")
    with pytest.raises(InputError, match="not a BMP"):
        frames.read_bmp(str(tmp_path / "x.bmp"))
    with pytest.raises(InputError, match="no such file"):
        frames.open_frames(str(tmp_path / "nothing.mp4"))
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(InputError, match="not a video or image"):
        frames.open_frames(str(tmp_path / "notes.txt"))
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="no image files"):
        frames.open_frames(str(empty))


def test_missing_models_or_interpreter_say_how_to_get_them(monkeypatch, tmp_path):
    monkeypatch.setattr(runtime, "_candidate_dirs", lambda: [str(tmp_path)])
    with pytest.raises(runtime.DetectorUnavailable, match="fetch_pose_models"):
        runtime.find_model(runtime.DETECTOR_FILE)
    ok, why = runtime.available()
    assert not ok and why.startswith("Pose detector models missing") and "fetch_pose_models" in why
    monkeypatch.setattr(runtime.importlib, "import_module", lambda name: (_ for _ in ()).throw(ImportError(name)))
    with pytest.raises(runtime.DetectorUnavailable, match="no TensorFlow Lite interpreter"):
        runtime.interpreter_class()
    monkeypatch.setattr(runtime, "INTERPRETERS", (("no_such_tflite_package.interpreter", "Interpreter"),))
    ok, why = runtime.available()
    assert not ok and why.startswith("Pose detector runtime missing") and "pip install ai-edge-litert" in why


@pytest.mark.parametrize("size,count", [((1280, 720), 6), ((720, 1280), 6), ((768, 576), 6), ((500, 500), 9),
                                        ((1920, 400), 3)])
def test_tiles_cover_the_frame_at_half_its_long_side(size, count):
    w, h = size
    regions = tiles(w, h)
    assert len(regions) == count
    assert all(r.side == max(w, h) / 2 and r.rotation == 0.0 for r in regions)
    covered = np.zeros((h, w), bool)
    for r in regions:
        (x0, y0), (x1, y1) = r.to_image(np.array([[0.0, 0.0], [1.0, 1.0]]))
        covered[max(0, int(np.floor(y0))):int(np.ceil(y1)), max(0, int(np.floor(x0))):int(np.ceil(x1))] = True
    assert covered.all()


def test_the_region_filter_holds_a_still_person_and_follows_a_moving_one():
    points = np.array([[400.0, 300.0], [400.0, 200.0]])
    steady = AlignmentFilter(fps=30.0)
    assert np.array_equal(steady(points), points)               # the first frame passes through
    noise = np.random.default_rng(1).normal(0, 2.0, (60, 2, 2))
    out = np.array([steady(points + n) for n in noise]) - points
    assert np.sqrt((out ** 2).mean()) < 0.7 * np.sqrt((noise ** 2).mean())   # a still person's jitter damped
    moved = [steady(points + (20.0 * k, 0.0)) for k in range(1, 16)]   # 600 px/s, 6 region sides a second
    assert abs(moved[-1][0, 0] - (points[0, 0] + 300.0)) < 25.0        # followed within a few frames
    steady.reset()
    far = points + 500.0
    assert np.array_equal(steady(far), far)                      # after a reset: a fresh start


def test_the_region_filter_is_set_in_seconds_not_frames():
    """The same motion sampled at 30 and at 120 frames/s is steadied alike at the same moment."""
    def run(fps):
        steady = AlignmentFilter(fps=fps)
        out = None
        for k in range(int(fps) + 1):                           # one second: 1 px/s drift plus a 50 px step at 0.5 s
            t = k / fps
            out = steady(np.array([[400.0 + t + 50.0 * (t >= 0.5), 300.0], [400.0, 200.0]]))
        return out[0, 0]
    assert abs(run(30.0) - run(120.0)) < 5.0


# ----------------------------------------------------------------------------- BlazePose on real photos

@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_landmarks_land_where_mediapipe_puts_them(networks, name):
    from core.pose_detection.tracker import PoseTracker

    pose = PoseTracker(networks, "per-frame").process(_photo(name))
    for k, xy in REFERENCE[name].items():
        assert np.hypot(*(pose.xy[k] - xy)) < 10.0, (name, k, pose.xy[k], xy)
        assert pose.visibility[k] > 0.9


def test_photo_becomes_canonical_tracks(networks):
    from core.pose_detection.detect import detect_frames
    from core.skeleton import JOINT_INDEX

    img = _photo("astronaut")
    result = detect_frames([img, img], fps=25.0, networks=networks)
    t = result.tracks
    assert t.n_frames == 2 and t.fps == 25.0 and t.image_size == (512.0, 512.0)
    thorax = t.xy[0, JOINT_INDEX["thorax"]]
    assert np.allclose(thorax, (np.array(REFERENCE["astronaut"][11]) + REFERENCE["astronaut"][12]) / 2, atol=10)
    # person's left is the image's right for someone facing the camera; the head is above the thorax
    assert t.xy[0, JOINT_INDEX["l_shoulder"], 0] > thorax[0] > t.xy[0, JOINT_INDEX["r_shoulder"], 0]
    assert t.xy[0, JOINT_INDEX["head"], 1] < thorax[1]
    assert t.conf[0, JOINT_INDEX["l_shoulder"]] > 0.9
    assert t.meta["detector"].startswith("BlazePose") and result.found_share == 1.0


def _moving_photo(name, n, size=(1280, 720)):
    """The photo at a moving place in a larger frame, the border replicated (a pan over a still scene)."""
    img = _photo(name)
    w, h = size
    offsets = [(300 + 7 * i, 120 - 3 * i) for i in range(n)]
    return [np.pad(img, ((oy, h - 512 - oy), (ox, w - 512 - ox), (0, 0)), mode="edge") for ox, oy in offsets], offsets


@pytest.mark.parametrize("mode,runs", [("tracking", 1), ("per-frame", 8)])
def test_a_panning_shot_is_followed(networks, mode, runs):
    from core.pose_detection.detect import detect_frames

    clip, offsets = _moving_photo("astronaut", 8)
    result = detect_frames(clip, fps=30.0, networks=networks, mode=mode)
    assert result.detector_runs == runs and result.found_share == 1.0
    rel = result.landmarks - np.array(offsets, dtype=float)[:, None]
    for k in (0, 2, 5):   # face points: where MediaPipe finds them in the photo, in every frame
        assert np.hypot(*(rel[:, k] - REFERENCE["astronaut"][k]).T).max() < 10.0
    # shoulders: on the person, either side of the nose, below the eyes
    assert (rel[:, 11, 0] > rel[:, 0, 0]).all() and (rel[:, 12, 0] < rel[:, 0, 0]).all()
    assert (rel[:, 11:13, 1] > rel[:, 2:3, 1]).all()


def test_no_person_is_one_line_and_cancel_keeps_what_was_found(networks):
    from core.pose_detection.detect import detect_frames

    grey = [np.full((240, 320, 3), 128, np.uint8)] * 3
    with pytest.raises(InputError, match="no person found in any of the 3 frames"):
        detect_frames(grey, fps=30.0, networks=networks)
    img = _photo("astronaut")
    calls = []
    result = detect_frames([img] * 6, fps=30.0, networks=networks, should_cancel=lambda: len(calls) >= 2,
                           progress=lambda done, total: calls.append(done))
    assert result.cancelled and result.tracks.n_frames == 2 and result.tracks.meta["cancelled_after"] == 2
    mixed = detect_frames([img, np.full_like(img, 128), img], fps=30.0, networks=networks)
    assert mixed.tracks.n_frames == 3 and np.isnan(mixed.tracks.xy[1]).all()
    assert "no person in 1 of 3 frames" in mixed.notes[0]


def test_command_line_on_a_folder_of_frames(networks, tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    img = _photo("astronaut")
    for i in range(4):
        _write_bmp(folder / f"f_{i:03d}.bmp", img, 24, False)
    out = tmp_path / "tracks.json"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-m", "core", "detect", str(folder), "--out", str(out), "--step", "2",
                           "--quiet"], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "2 frames, person in 100 %" in proc.stdout
    from core.io.formats import read_any

    tracks = read_any(str(out))
    assert tracks.n_frames == 2 and tracks.fps == 15.0   # 30 fps assumed for images, every 2nd frame
    assert tracks.meta["source"] == str(folder)          # the file says where it came from and how
    assert tracks.meta["detector"].startswith("BlazePose") and tracks.meta["step"] == 2
    bad = subprocess.run([sys.executable, "-m", "core", "detect", str(folder), "--out", str(out), "--start", "9"],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0 and "past the last frame" in bad.stderr


# ----------------------------------------------------------------------------- a phone's rotation flag

def _box(kind: bytes, payload: bytes, wide: bool = False) -> bytes:
    import struct

    if wide:
        return struct.pack(">I4sQ", 1, kind, 16 + len(payload)) + payload
    return struct.pack(">I4s", 8 + len(payload), kind) + payload


def _tkhd(degrees: int, version: int = 0, size=(1280, 720)) -> bytes:
    import struct

    c, s = round(math.cos(math.radians(degrees))), round(math.sin(math.radians(degrees)))
    times = struct.pack(">QQIIQ", 0, 0, 1, 0, 100) if version == 1 else struct.pack(">IIIII", 0, 0, 1, 0, 100)
    matrix = struct.pack(">9i", c << 16, s << 16, 0, -s << 16, c << 16, 0, 0, 0, 1 << 30)
    body = times + bytes(8) + struct.pack(">hhhH", 0, 0, 0, 0) + matrix + struct.pack(">II", size[0] << 16,
                                                                                       size[1] << 16)
    return bytes([version, 0, 0, 3]) + body


def _mp4(tmp_path, name, degrees, *, version=0, moov_last=False, audio_first=False):
    traks = _box(b"trak", _box(b"tkhd", _tkhd(degrees, version)))
    if audio_first:   # an audio track has no picture size: skipped
        traks = _box(b"trak", _box(b"tkhd", _tkhd(0, 0, size=(0, 0)))) + traks
    moov = _box(b"moov", _box(b"mvhd", bytes(100)) + traks)
    parts = [_box(b"ftyp", b"isom\0\0\2\0isomiso2mp41"), _box(b"mdat", bytes(5000), wide=True)]
    parts = parts + [moov] if moov_last else [parts[0], moov, parts[1]]
    path = tmp_path / name
    path.write_bytes(b"".join(parts))
    return str(path)


@pytest.mark.parametrize("degrees", [0, 90, 180, 270])
@pytest.mark.parametrize("version", [0, 1])
def test_display_rotation_is_read_from_the_track_header(tmp_path, degrees, version):
    from core.pose_detection.video_meta import display_rotation

    assert display_rotation(_mp4(tmp_path, "a.mp4", degrees, version=version)) == degrees
    late = _mp4(tmp_path, "b.mov", degrees, version=version, moov_last=True, audio_first=True)
    assert display_rotation(late) == degrees
    assert display_rotation(late, limit=600) == degrees   # the header is found at the end of a long file


def test_display_rotation_of_other_files_is_zero(tmp_path):
    from core.pose_detection.video_meta import display_rotation

    (tmp_path / "x.mp4").write_bytes(b"\0\0\0\x10junkjunkjunk" + bytes(50))
    assert display_rotation(str(tmp_path / "x.mp4")) == 0
    assert display_rotation(str(tmp_path / "missing.mp4")) == 0
    assert display_rotation(str(PHOTOS)) == 0


@pytest.mark.parametrize("size", [(601, 533), (533, 777), (1281, 721)])
def test_odd_frame_sizes(networks, size):
    from core.pose_detection.tracker import PoseTracker

    w, h = size
    img = _photo("astronaut")
    ox, oy = (w - 512) // 2, (h - 512) // 3
    frame = np.pad(img, ((oy, h - 512 - oy), (ox, w - 512 - ox), (0, 0)), mode="edge")
    pose = PoseTracker(networks, "per-frame").process(frame)
    for k in (0, 2, 5):
        assert np.hypot(*(pose.xy[k] - REFERENCE["astronaut"][k] - (ox, oy))) < 10.0, (size, k)


def test_a_far_person_is_found_on_tiles(networks):
    """A person a quarter of the frame tall: the whole frame's detector misses them, its tiles do not."""
    from core.pose_detection.tracker import PoseTracker

    img = _photo("astronaut")[:510, :510].reshape(170, 3, 170, 3, 3).mean((1, 3)).astype(np.uint8)
    frame = np.full((720, 1280, 3), 128, np.uint8)
    frame[400:570, 900:1070] = img
    assert blazepose.decode_detections(*networks.detect(blazepose.detector_input(frame)[0]),
                                       whole_frame(1280, 720)) == []
    found, runs = blazepose.find_people(frame, networks.detect)
    assert len(found) >= 1 and runs == 7
    pose = PoseTracker(networks, "per-frame").process(frame)
    for k in (0, 2, 5):
        assert np.hypot(*(pose.xy[k] - (np.array(REFERENCE["astronaut"][k]) / 3 + (900, 400)))) < 6.0, k


def test_a_jump_to_another_place_is_noted(networks):
    """The person vanishes from one place and appears far off (someone else, as far as the tracks can
    tell): the detection keeps both and says where the tracks jump."""
    from core.pose_detection.detect import detect_frames

    img = _photo("astronaut")
    here = np.pad(img, ((100, 108), (40, 728), (0, 0)), mode="edge")
    there = np.pad(img, ((100, 108), (728, 40), (0, 0)), mode="edge")
    result = detect_frames([here] * 6 + [there] * 6, fps=30.0, networks=networks)
    assert result.found_share == 1.0
    assert any("jump to another person at frame 6" in note for note in result.notes), result.notes
    steady = detect_frames([here] * 8, fps=30.0, networks=networks)
    assert not any("another person" in note for note in steady.notes)


class _TwoPeople:
    """A scripted stand-in for BlazePose's two networks: people at fixed places whose detector scores the
    test sets per frame (``None``: not seen), and a landmark network that answers at the region's centre."""

    def __init__(self):
        self.cells = {"A": (5, 3), "B": (5, 10)}      # stride-16 grid cells (row, column)
        self.scores = {}

    def place(self, who):   # image pixels of a person's hip centre in a 448 x 448 frame
        row, col = self.cells[who]
        return np.array([(col + 0.5) / 14 * 448, (row + 0.5) / 14 * 448])

    def detect(self, tensor):
        raw = np.zeros((1, 2254, 12))
        logits = np.full((1, 2254, 1), -20.0)
        for who, score in self.scores.items():
            if score is None:
                continue
            row, col = self.cells[who]
            k = 1568 + 2 * (row * 14 + col)
            raw[0, k, 2:4] = 40.0
            raw[0, k, 6:8] = (0.0, -40.0)             # keypoint 1 above keypoint 0 (at the anchor)
            logits[0, k] = math.log(score / (1 - score))
        return raw, logits

    def landmark(self, tensor):
        rows = np.zeros((39, 5))
        rows[:, :2] = 128.0
        rows[34, :2] = (128.0, 128.0 - 256 / 2.5)     # keeps the region as it is
        rows[:, 3] = 5.0
        return rows.reshape(1, -1), np.array([[1.0]]), None


@pytest.mark.parametrize("mode", ["per-frame", "tracking"])
def test_the_followed_person_is_kept_when_someone_else_scores_higher(mode):
    from core.pose_detection.tracker import PoseTracker

    nets = _TwoPeople()
    tracker = PoseTracker(nets, mode, fps=30.0)
    frame = np.zeros((448, 448, 3), np.uint8)
    nets.scores = {"A": 0.9, "B": 0.8}
    assert np.allclose(tracker.process(frame).xy[0], nets.place("A"))
    nets.scores = {"A": 0.7, "B": 0.95}               # the other person is now the detector's favourite
    if mode == "tracking":
        tracker.region = None                          # as after a lost frame: the detector runs again
    assert np.allclose(tracker.process(frame).xy[0], nets.place("A"))
    nets.scores = {"A": None, "B": 0.95}               # the followed person is gone: the other one is taken
    tracker.region = None
    assert np.allclose(tracker.process(frame).xy[0], nets.place("B"))
    fresh = PoseTracker(nets, mode, fps=30.0)          # nobody followed yet: the best score wins
    nets.scores = {"A": 0.7, "B": 0.95}
    assert np.allclose(fresh.process(frame).xy[0], nets.place("B"))


def test_a_followed_person_whose_score_dips_once_is_looked_at_wider_before_the_detector_runs():
    from core.pose_detection.tracker import RETRY_WIDER, PoseTracker

    nets = _TwoPeople()
    seen = []
    answer = nets.landmark

    def landmark(tensor):            # the second look at the same frame answers; the first does not
        rows, flag, heat = answer(tensor)
        seen.append(tensor)
        return rows, np.array([[0.3 if len(seen) == 2 else 1.0]]), heat
    nets.landmark = landmark
    tracker = PoseTracker(nets, "tracking", fps=30.0)
    frame = np.zeros((448, 448, 3), np.uint8)
    nets.scores = {"A": 0.9}
    first = tracker.process(frame)
    side = tracker.region.side
    second = tracker.process(frame)
    assert tracker.detector_runs == 1 and len(seen) == 3          # no second detector run: kept by the wider look
    assert np.allclose(second.xy[0], first.xy[0])
    assert side < tracker.region.side <= side * RETRY_WIDER      # the answer came from the wider region


# ----------------------------------------------------------------------------- video files without Blender

def _write_mp4(path, n=6, fps=24):
    import imageio_ffmpeg

    img = _photo("astronaut")
    writer = imageio_ffmpeg.write_frames(str(path), (1280, 720), fps=fps, macro_block_size=1)
    writer.send(None)
    offsets = []
    for i in range(n):
        ox = 300 + 4 * i
        offsets.append((ox, 100))
        writer.send(np.ascontiguousarray(np.pad(img, ((100, 108), (ox, 1280 - 512 - ox), (0, 0)), mode="edge")))
    writer.close()
    return offsets


def test_command_line_on_a_video_file(networks, tmp_path):
    from core.io.formats import read_any

    offsets = _write_mp4(tmp_path / "clip.mp4")
    out = tmp_path / "tracks.json"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-m", "core", "detect", str(tmp_path / "clip.mp4"), "--out", str(out),
                           "--quiet"], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    tracks = read_any(str(out))
    assert tracks.n_frames == 6 and tracks.fps == 24.0 and tracks.image_size == (1280.0, 720.0)
    # the same as detecting on the frames before they were encoded, give or take H.264's losses
    from core.pose_detection.detect import detect_frames
    from core.skeleton import JOINT_INDEX

    img = _photo("astronaut")
    raw = [np.pad(img, ((100, 108), (ox, 1280 - 512 - ox), (0, 0)), mode="edge") for ox, _ in offsets]
    direct = detect_frames(raw, fps=24.0, networks=networks).tracks
    for joint in ("head", "thorax", "l_shoulder", "r_shoulder"):
        j = JOINT_INDEX[joint]
        gap = np.hypot(*(tracks.xy[:, j] - direct.xy[:, j]).T)
        assert np.median(gap) < 5.0 and gap.max() < 15.0, (joint, gap)   # measured: 1.6-8.5 px, worst on frame 0


def test_a_turned_video_is_read_upright_and_without_a_decoder_one_line(networks, tmp_path, monkeypatch):
    from core.pose_detection.detect import detect_frames
    from core.pose_detection.video_meta import display_rotation
    from core.skeleton import JOINT_INDEX
    from tests.mp4_headers import turn_quarter

    _write_mp4(tmp_path / "phone.mp4", n=3)
    turn_quarter(tmp_path / "phone.mp4")
    assert display_rotation(str(tmp_path / "phone.mp4")) in (90, 270)
    source = frames.open_frames(str(tmp_path / "phone.mp4"))
    assert (source.width, source.height, source.count) == (720, 1280, 3)
    result = detect_frames(source.frames(), fps=source.fps, networks=networks)
    up = np.nanmedian(result.tracks.xy[:, JOINT_INDEX["head"]] - result.tracks.xy[:, JOINT_INDEX["thorax"]], 0)
    assert abs(up[0]) > 3 * abs(up[1])                   # turned as a player shows it: the person lies sideways
    monkeypatch.setattr(frames, "_imageio_ffmpeg", lambda: None)
    with pytest.raises(InputError, match="needs imageio-ffmpeg .* batch.py --video"):
        frames.open_frames(str(tmp_path / "phone.mp4"))


# ----------------------------------------------------------------------------- what tracks show without truth

def test_track_quality_counts_flips_drop_outs_switches_and_still_jitter():
    from core.pose_detection.quality import track_quality
    from core.skeleton import JOINT_INDEX
    from core.synthetic.motion import load_motion
    from core.synthetic.synth import synthesize
    from core.tracks import Tracks

    walk, _ = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=120), kinds="still", noise_px=0.0, seed=2)
    xy = walk.xy.copy()
    la, ra = JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]
    xy[50:53, [la, ra]] = xy[50:53, [ra, la]]                        # one 3-frame ankle exchange: two flips
    still = np.repeat(xy[-1:], 30, axis=0) + np.random.default_rng(0).normal(0, 0.5, (30, 17, 2))   # stops, holds
    other = still + np.array([300.0, 0.0])                          # someone else, far to the right
    conf = np.ones((180, 17))
    conf[10:25, JOINT_INDEX["l_wrist"]] = 0.0                        # half a second without the left wrist
    tracks = Tracks(np.concatenate([xy, still, other]), conf, 30.0, walk.image_size)
    q = track_quality(tracks)
    assert q["swaps"]["ankle"]["flips"] == 2 and q["swaps"]["knee"]["flips"] == 0
    assert q["person_switches"] == 1 and q["switch_frames"] == [150]
    assert q["longest_stretch"] == {"start": 0, "frames": 150, "seconds": 5.0}
    assert q["dropouts"]["l_wrist"]["longest_s"] == pytest.approx(0.5) and q["dropouts"]["pelvis"]["share"] == 0.0
    assert q["still_frames"] >= 25                                   # the held pose, with 0.5 px of jitter
    assert 0.4 < q["jitter"]["pelvis"]["median_px"] < 1.2
