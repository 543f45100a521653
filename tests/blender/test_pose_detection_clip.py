"""Detect Pose in Clip and ``batch.py --video`` on real bpy, with footage the test makes from a real photo.

The footage is scikit-image's public-domain ``astronaut`` photo (tests/core/data/person_photos.npz)
moving across a 1280 x 720 frame, its border replicated: written by Blender as a PNG sequence, and
rendered by Blender into an H.264 mp4 for the batch run.  Blender decodes the clip for the detector;
the markers it writes must hold exactly what the core finds on the same pixels.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.mp4_headers import turn_quarter

ROOT = Path(__file__).resolve().parents[2]
PHOTOS = ROOT / "tests" / "core" / "data" / "person_photos.npz"
W, H = 1280, 720


def _frames(n: int, person: bool = True):
    img = np.load(PHOTOS)["astronaut"]
    out = []
    for i in range(n):
        ox, oy = 300 + 9 * i, 120 - 4 * i
        if person:
            out.append(np.pad(img, ((oy, H - 512 - oy), (ox, W - 512 - ox), (0, 0)), mode="edge"))
        else:
            out.append(np.full((H, W, 3), 128, np.uint8))
    return out


def _png_sequence(folder: Path, frames) -> Path:
    import bpy

    folder.mkdir(parents=True, exist_ok=True)
    image = bpy.data.images.new("frame", W, H)
    image.file_format = "PNG"
    for i, frame in enumerate(frames):
        rgba = np.concatenate([frame[::-1].astype(np.float32) / 255.0, np.ones((H, W, 1), np.float32)], axis=2)
        image.pixels.foreach_set(rgba.ravel())
        image.filepath_raw = str(folder / f"shot_{i + 1:04d}.png")
        image.save()
    bpy.data.images.remove(image)
    return folder / "shot_0001.png"


def _mp4(path: Path, first_png: Path, n: int) -> Path:
    """An H.264 mp4 of the PNG sequence, rendered by Blender's sequencer in a scratch scene."""
    import bpy

    from monoskel.blender.compat import sequencer_strips, set_output_format

    scene = bpy.data.scenes.new("encode")
    try:
        editor = scene.sequence_editor_create()
        strip = sequencer_strips(editor).new_image(name="im", filepath=str(first_png), channel=1, frame_start=1)
        for i in range(2, n + 1):
            strip.elements.append(f"shot_{i:04d}.png")
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
        scene.frame_start, scene.frame_end, scene.render.fps = 1, n, 25
        set_output_format(scene.render.image_settings, "FFMPEG")
        scene.render.ffmpeg.format, scene.render.ffmpeg.codec = "MPEG4", "H264"
        scene.render.ffmpeg.constant_rate_factor = "PERC_LOSSLESS"
        scene.view_settings.view_transform = "Standard"
        scene.render.use_sequencer = True
        scene.render.filepath = str(path)
        with bpy.context.temp_override(scene=scene):
            bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        bpy.data.scenes.remove(scene)
    made = sorted(path.parent.glob(path.stem + "*.mp4"))
    assert made, "Blender wrote no mp4"
    return made[0]


def test_detect_pose_writes_joint_markers_and_scene_tracks(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import movie_clip, scene_data
    from monoskel.core.pose_detection.detect import detect_frames
    from monoskel.core.skeleton import JOINT_INDEX, JOINTS

    frames = _frames(5)
    clip = bpy.data.movieclips.load(str(_png_sequence(tmp_path / "seq", frames)))
    empty_scene.active_clip = clip
    scenes = set(bpy.data.scenes.keys())
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}
    assert set(bpy.data.scenes.keys()) == scenes          # the decoding scene is gone

    names = {t.name for t in clip.tracking.tracks}
    assert set(JOINTS) <= names
    assert all(clip.tracking.tracks[j].weight == 0.0 for j in JOINTS)
    fps = empty_scene.render.fps / empty_scene.render.fps_base     # the clip's rate: the region filter is in seconds
    expected = detect_frames(frames, fps=fps).tracks       # the core on the same pixels
    from_markers = movie_clip.tracks_from_clip(clip, fps=25.0)
    assert from_markers.n_frames == 5
    assert np.allclose(from_markers.xy, expected.xy, atol=0.05, equal_nan=True)
    stored = scene_data.load_tracks(empty_scene)
    assert stored.n_frames == 5 and np.allclose(stored.xy, expected.xy, atol=1e-6, equal_nan=True)
    # the detector's own 3D joints are kept with the scene's tracks (metres, 0.1 mm in the stored file)
    assert stored.landmarks_3d is not None
    assert np.allclose(stored.landmarks_3d, expected.landmarks_3d, atol=1e-4, equal_nan=True)
    assert empty_scene.monoskel.has_tracks
    thorax = stored.xy[:, JOINT_INDEX["thorax"]]
    assert np.all(np.diff(thorax[:, 0]) > 0)              # the person moves right, as painted

    # Tracks from Clip (after hand corrections) keeps the detector's 3D joints beside the markers' 2D
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    again = scene_data.load_tracks(empty_scene)
    assert again.meta.get("clip") == clip.name and again.n_frames == 5
    assert np.allclose(again.landmarks_3d, stored.landmarks_3d, atol=1e-6, equal_nan=True)
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}

    # Run again on frames 2-3 only: those markers are replaced, the others kept.
    clip.tracking.tracks["pelvis"].markers.find_frame(5, exact=True).co = (0.5, 0.5)
    assert bpy.ops.monoskel.detect_pose(start=2, end=3) == {"FINISHED"}
    assert tuple(clip.tracking.tracks["pelvis"].markers.find_frame(5, exact=True).co) == pytest.approx((0.5, 0.5))
    assert scene_data.load_tracks(empty_scene).n_frames == 2


def test_no_person_fails_with_one_line_and_changes_nothing(empty_scene, tmp_path):
    import bpy

    clip = bpy.data.movieclips.load(str(_png_sequence(tmp_path / "grey", _frames(3, person=False))))
    empty_scene.active_clip = clip
    scenes, texts = set(bpy.data.scenes.keys()), len(bpy.data.texts)
    with pytest.raises(RuntimeError, match="no person found in any of the 3 frames"):
        bpy.ops.monoskel.detect_pose()
    assert len(clip.tracking.tracks) == 0 and not empty_scene.monoskel.has_tracks
    assert set(bpy.data.scenes.keys()) == scenes and len(bpy.data.texts) == texts
    with pytest.raises(RuntimeError, match="past its last frame"):
        bpy.ops.monoskel.detect_pose(start=9)


def test_sidebar_says_how_to_get_a_missing_detector(empty_scene, tmp_path, monkeypatch):
    import bpy

    from monoskel.operators import detect_pose
    from monoskel.ui import state

    clip = bpy.data.movieclips.load(str(_png_sequence(tmp_path / "seq", _frames(1))))
    empty_scene.active_clip = clip
    row = next(r for r in state.input_rows(empty_scene.monoskel, has_clip=True) if r.op == "monoskel.detect_pose")
    assert row.enabled
    monkeypatch.setattr(detect_pose, "_AVAILABLE", [(False, "no TensorFlow Lite interpreter is installed; pip "
                                                            "install ai-edge-litert")])
    row = next(r for r in state.input_rows(empty_scene.monoskel, has_clip=True) if r.op == "monoskel.detect_pose")
    assert not row.enabled and "ai-edge-litert" in row.reason
    assert not bpy.ops.monoskel.detect_pose.poll()


def _batch(*args):
    return subprocess.run([sys.executable, str(ROOT / "batch.py"), *map(str, args)], capture_output=True, text=True,
                          timeout=600)


def test_batch_video_to_armature_and_camera(blender, tmp_path):
    import bpy

    from monoskel.core.io.formats import read_any
    from monoskel.core.skeleton import JOINTS

    n = 12
    from tests.mp4_headers import add_to_moov, quicktime_focal_meta

    video = _mp4(tmp_path / "clip.mp4", _png_sequence(tmp_path / "seq", _frames(n)), n)
    add_to_moov(video, quicktime_focal_meta(26, "int"), into_track=True)     # as a phone records its lens
    out, tracks_out = tmp_path / "scene.blend", tmp_path / "tracks.json"
    proc = _batch("--video", video, "--output", out, "--tracks-out", tracks_out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "person found in 100 % of 12 frames" in proc.stderr
    assert "lens 24.8 mm (36 mm film) from the file's metadata: 26 mm 35 mm-equivalent" in proc.stderr + proc.stdout
    tracks = read_any(str(tracks_out))
    assert tracks.n_frames == n and tracks.fps == pytest.approx(25.0)
    bpy.ops.wm.open_mainfile(filepath=str(out))
    try:
        assert any(o.type == "ARMATURE" for o in bpy.data.objects)
        assert any(o.type == "CAMERA" for o in bpy.data.objects)
        clip = bpy.context.scene.active_clip
        assert clip is not None and set(JOINTS) <= {t.name for t in clip.tracking.tracks}
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)


def test_batch_video_bad_input_is_one_line_and_writes_nothing(blender, tmp_path):
    fake = tmp_path / "notes.mp4"
    fake.write_text("this is not a video")
    out = tmp_path / "o.blend"
    proc = _batch("--video", fake, "--output", out)
    assert proc.returncode == 2 and not out.exists()
    assert proc.stderr.strip().splitlines()[-1].startswith("batch.py: error:")
    proc = _batch("--video", tmp_path / "missing.mp4", "--output", out)
    assert proc.returncode == 2 and "no such file" in proc.stderr and not out.exists()
    proc = _batch("--video", fake, "--builtin", "walk", "--output", out)
    assert proc.returncode == 2 and "exactly one input" in proc.stderr


def test_a_phone_videos_rotation_flag_is_followed_or_warned_about(empty_scene, tmp_path):
    import bpy

    from monoskel.blender.pose_detection.clip_detect import detect_clip, load_clip, rotation_warning
    from monoskel.core.pose_detection.video_meta import display_rotation
    from monoskel.core.skeleton import JOINT_INDEX

    video = _mp4(tmp_path / "phone.mp4", _png_sequence(tmp_path / "seq", _frames(3)), 3)
    turn_quarter(video)
    assert display_rotation(str(video)) in (90, 270)
    clip = load_clip(str(video))
    result = detect_clip(clip)
    up = np.nanmedian(result.tracks.xy[:, JOINT_INDEX["head"]] - result.tracks.xy[:, JOINT_INDEX["thorax"]], 0)
    if bpy.app.version >= (4, 5, 0):
        # Blender turns the picture: the clip is portrait, and the frames we detect in are turned too
        assert tuple(clip.size) == (H, W) and result.tracks.image_size == (H, W)
        assert abs(up[0]) > 3 * abs(up[1])          # the upright person of the source now lies sideways
        assert rotation_warning(clip) is None
    else:
        assert tuple(clip.size) == (W, H) and up[1] < -3 * abs(up[0])   # shown and detected as stored
        assert "ignores the flag" in rotation_warning(clip)


def test_an_image_sequence_with_a_gap_is_refused_with_one_line(empty_scene, tmp_path):
    import bpy

    first = _png_sequence(tmp_path / "gap", _frames(4))
    (tmp_path / "gap" / "shot_0003.png").unlink()
    clip = bpy.data.movieclips.load(str(first))
    empty_scene.active_clip = clip
    scenes = set(bpy.data.scenes.keys())
    with pytest.raises(RuntimeError, match="no image numbered 3 .the next is 4."):
        bpy.ops.monoskel.detect_pose()
    assert len(clip.tracking.tracks) == 0 and set(bpy.data.scenes.keys()) == scenes


def test_a_photo_poses_a_rig_without_placing_markers(empty_scene, tmp_path):
    """Single-image posing ("pose my character like the person in this photo") with the joints found by the detector."""
    import bpy

    photo = tmp_path / "photo.png"          # one real photo, its own size, alone in its folder
    img = np.load(PHOTOS)["astronaut"]
    image = bpy.data.images.new("photo", img.shape[1], img.shape[0])
    rgba = np.concatenate([img[::-1] / 255.0, np.ones(img.shape[:2] + (1,))], 2).astype(np.float32)
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw, image.file_format = str(photo), "PNG"
    image.save()
    bpy.data.images.remove(image)
    clip = bpy.data.movieclips.load(str(photo))
    empty_scene.active_clip = clip
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}
    assert empty_scene.monoskel.has_tracks and empty_scene.monoskel.tracks_frames == 1
    assert bpy.ops.monoskel.pose_from_image() == {"FINISHED"}
    settings = empty_scene.monoskel
    assert settings.si_has_pose and settings.si_armature is not None and settings.si_camera is not None


def test_the_lens_comes_from_the_clips_camera_or_the_movies_metadata(empty_scene, tmp_path):
    """Detect Pose in Clip keeps the lens the footage records in the scene's tracks: the movie's own
    35 mm-equivalent focal length (as a phone writes it), unless the Movie Clip's camera was set; the
    estimate then starts from it and says where it came from."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.movie_clip import clip_lens
    from monoskel.core.lens.prior import focal_from_35mm_equivalent, focal_from_sensor
    from tests.mp4_headers import add_to_moov, quicktime_focal_meta

    video = _mp4(tmp_path / "phone.mp4", _png_sequence(tmp_path / "seq", _frames(3)), 3)
    add_to_moov(video, quicktime_focal_meta(26, "int"), into_track=True)
    clip = bpy.data.movieclips.load(str(video))
    assert clip.frame_duration == 3                       # the added atom leaves the movie playable
    empty_scene.active_clip = clip
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}
    meta = scene_data.load_tracks(empty_scene).meta
    assert meta["lens_focal_mm"] == pytest.approx(focal_from_35mm_equivalent(26, (W, H)), abs=1e-3)
    assert "file's metadata: 26 mm 35 mm-equivalent" in meta["lens_source"]
    # the clip's camera, once the user sets it, comes first
    clip.tracking.camera.sensor_width, clip.tracking.camera.focal_length = 6.0, 4.5
    lens = clip_lens(clip)
    assert lens.focal_mm == pytest.approx(focal_from_sensor(4.5, 6.0, (W, H))) and "Movie Clip's camera" in lens.source
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}
    assert scene_data.load_tracks(empty_scene).meta["lens_focal_mm"] == pytest.approx(27.0, abs=1e-3)


def test_a_phone_movie_that_states_no_lens_gets_the_main_camera_assumed(empty_scene, tmp_path):
    """An Android phone's own recorder names the phone in the movie's metadata but writes no lens: Detect Pose
    in Clip keeps the phone's main camera, marked as assumed, and says where it came from."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.lens.prior import PHONE_VIDEO_EQUIVALENT_MM, focal_from_35mm_equivalent
    from tests.mp4_headers import add_to_moov, quicktime_text_meta

    video = _mp4(tmp_path / "android.mp4", _png_sequence(tmp_path / "seq", _frames(3)), 3)
    add_to_moov(video, quicktime_text_meta({"com.android.version": "14", "com.android.manufacturer": "Google",
                                            "com.android.model": "Pixel 9"}))
    clip = bpy.data.movieclips.load(str(video))
    empty_scene.active_clip = clip
    assert bpy.ops.monoskel.detect_pose() == {"FINISHED"}
    meta = scene_data.load_tracks(empty_scene).meta
    assert meta["lens_focal_mm"] == pytest.approx(focal_from_35mm_equivalent(PHONE_VIDEO_EQUIVALENT_MM, (W, H)),
                                                  abs=1e-3)
    assert meta["lens_assumed"] is True and "a phone's main camera, assumed" in meta["lens_source"]
    assert "Google Pixel 9" in meta["lens_source"]
