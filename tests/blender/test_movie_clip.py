"""Joint tracks from the Movie Clip Editor: create the 17 named tracks, move markers, convert to pixels."""

from __future__ import annotations

import math

import numpy as np
import pytest

WIDTH, HEIGHT, N_FRAMES = 80, 60, 6


def _clip(tmp_path, frame_start=1):
    """A real movie clip: a PNG sequence written with Blender's image API, loaded as a clip."""
    import bpy

    image = bpy.data.images.new("frame", WIDTH, HEIGHT)
    image.file_format = "PNG"
    for i in range(N_FRAMES):
        image.filepath_raw = str(tmp_path / f"shot_{i + 1:04d}.png")
        image.save()
    bpy.data.images.remove(image)
    clip = bpy.data.movieclips.load(str(tmp_path / "shot_0001.png"))
    clip.frame_start = frame_start
    bpy.context.scene.active_clip = clip
    return clip


def test_add_joint_tracks_creates_17_named_tracks_on_the_current_frame(empty_scene, tmp_path):
    import bpy

    from monoskel.core.skeleton import JOINTS

    clip = _clip(tmp_path, frame_start=10)
    empty_scene.frame_current = 12  # clip frame 3
    assert bpy.ops.monoskel.clip_add_joint_tracks() == {"FINISHED"}
    names = [t.name for t in clip.tracking.tracks]
    assert sorted(names) == sorted(JOINTS)
    for track in clip.tracking.tracks:
        assert [m.frame for m in track.markers] == [3]
        assert track.weight == 0.0      # no say in Blender's own camera solve: a person is not scenery
        x, y = track.markers[0].co
        assert 0 < x < 1 and 0 < y < 1
    head = clip.tracking.tracks["head"].markers[0].co
    ankle = clip.tracking.tracks["l_ankle"].markers[0].co
    assert head[1] > ankle[1]  # laid out as a standing figure (normalised y is up)

    # Running it again keeps the animator's work and adds nothing.
    assert bpy.ops.monoskel.clip_add_joint_tracks() == {"FINISHED"}
    assert len(clip.tracking.tracks) == 17


def test_tracks_from_clip_converts_markers_to_top_left_pixels(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.skeleton import JOINT_INDEX

    clip = _clip(tmp_path)
    empty_scene.frame_current = 1
    bpy.ops.monoskel.clip_add_joint_tracks()
    tracks = clip.tracking.tracks
    tracks["pelvis"].markers.find_frame(1, exact=True).co = (0.25, 0.75)
    tracks["pelvis"].markers.insert_frame(4, co=(0.5, 0.1))
    tracks["head"].markers.insert_frame(2, co=(0.9, 0.2))
    tracks["head"].markers.find_frame(2, exact=True).mute = True    # disabled -> missing
    tracks["l_wrist"].markers.insert_frame(5, co=(1.0, 0.0))

    empty_scene.render.fps = 25
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    got = scene_data.load_tracks(empty_scene)
    assert got.n_frames == N_FRAMES and got.image_size == (WIDTH, HEIGHT)
    assert got.fps == pytest.approx(25.0)  # image sequences have no rate: the scene's is used
    p, h, w = JOINT_INDEX["pelvis"], JOINT_INDEX["head"], JOINT_INDEX["l_wrist"]
    np.testing.assert_allclose(got.xy[0, p], (0.25 * WIDTH, 0.25 * HEIGHT), atol=1e-3)
    np.testing.assert_allclose(got.xy[3, p], (0.5 * WIDTH, 0.9 * HEIGHT), atol=1e-3)
    np.testing.assert_allclose(got.xy[4, w], (WIDTH, HEIGHT), atol=1e-3)
    # Only exact, enabled markers are data: no marker on frame 2 for the pelvis, a muted one for the head.
    assert not got.present[1, p] and not got.present[1, h]
    assert got.present[0, h]
    assert empty_scene.monoskel.has_tracks and empty_scene.monoskel.tracks_frames == N_FRAMES
    assert empty_scene.frame_start == clip.frame_start
    # The tracking camera still holds Blender's defaults: the focal length stays to be estimated.
    assert empty_scene.monoskel.estimate_focal


def test_clip_camera_focal_becomes_the_initial_focal(empty_scene, tmp_path):
    import bpy

    from monoskel.core.camera import mm_per_pixel

    clip = _clip(tmp_path)
    bpy.ops.monoskel.clip_add_joint_tracks()
    clip.tracking.camera.sensor_width = 23.5
    clip.tracking.camera.focal_length = 35.0
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    s = empty_scene.monoskel
    focal_px = 35.0 / 23.5 * WIDTH
    assert not s.estimate_focal
    assert s.focal_mm == pytest.approx(focal_px * mm_per_pixel((WIDTH, HEIGHT)), rel=1e-5)
    # 4:3 frames are height-limited on the 36 x 24 film, so this is not simply 35 * 36 / 23.5.
    assert not math.isclose(s.focal_mm, 35.0 * 36.0 / 23.5, rel_tol=1e-3)


def test_clip_without_joint_tracks_reports_and_changes_nothing(empty_scene, tmp_path):
    import bpy

    clip = _clip(tmp_path)
    clip.tracking.tracks.new(name="Track", frame=1)
    texts = len(bpy.data.texts)
    with pytest.raises(RuntimeError, match="no tracks named after the canonical joints"):
        bpy.ops.monoskel.clip_to_tracks()
    assert len(bpy.data.texts) == texts and not empty_scene.monoskel.has_tracks


def test_clip_operators_say_why_without_a_clip(empty_scene):
    import bpy

    assert not bpy.ops.monoskel.clip_add_joint_tracks.poll()
    with pytest.raises(RuntimeError, match="Open a movie clip"):
        bpy.ops.monoskel.clip_to_tracks()
