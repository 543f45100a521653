"""Background tracks in Blender: clip markers that are not joints become static tracks, the
sidebar's "Use Background Tracks" switch, and Blender's own tripod camera solve read and compared."""

from __future__ import annotations

import numpy as np
import pytest

WIDTH, HEIGHT = 720, 480
N_FRAMES = 90


@pytest.fixture(scope="module")
def filmed():
    """A handheld walk, 35 mm, with 12 static points (core tracks and truth)."""
    from monoskel.core.synthetic.footage_sim import HandheldOperator
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    motion = load_motion("builtin:walk", max_frames=N_FRAMES)
    return synthesize(motion, focal_mm=35.0, operator=HandheldOperator(moves_per_s=1.0), seed=4, static_points=12)


def _clip_with_markers(tmp_path, tracks):
    """A blank PNG sequence loaded as a clip, with one track per joint and per static point holding the
    tracks' positions as markers (the solver reads markers, not pixels)."""
    import bpy

    from monoskel.core.skeleton import JOINTS

    image = bpy.data.images.new("frame", WIDTH, HEIGHT)
    image.file_format = "PNG"
    for i in range(N_FRAMES):
        image.filepath_raw = str(tmp_path / f"bg_{i + 1:04d}.png")
        image.save()
    bpy.data.images.remove(image)
    clip = bpy.data.movieclips.load(str(tmp_path / "bg_0001.png"))
    bpy.context.scene.active_clip = clip
    columns = [(name, tracks.xy[:, j]) for j, name in enumerate(JOINTS)]
    columns += [(name, tracks.static.xy[:, k]) for k, name in enumerate(tracks.static.names)]
    for name, xy in columns:
        seen = np.flatnonzero(np.isfinite(xy[:, 0]))
        if seen.size == 0:
            continue
        track = clip.tracking.tracks.new(name=name, frame=int(seen[0]) + 1)
        if name in JOINTS:
            track.weight = 0.0          # the person moves: no say in the camera solve (as Add Joint Tracks does)
        for i in seen:
            co = (float(xy[i, 0]) / WIDTH, 1.0 - float(xy[i, 1]) / HEIGHT)
            marker = track.markers.find_frame(int(i) + 1, exact=True) or track.markers.insert_frame(int(i) + 1)
            marker.co = co
    return clip


def _tripod_solve(clip, focal_mm: float) -> None:
    """What the animator does in the Movie Clip Editor: tripod mode, the lens, Solve Camera Motion."""
    import bpy

    clip.tracking.settings.use_tripod_solver = True
    clip.tracking.camera.sensor_width = 36.0
    clip.tracking.camera.focal_length = focal_mm
    window = bpy.context.window_manager.windows[0]
    area = window.screen.areas[0]
    area.type = "CLIP_EDITOR"
    area.spaces.active.clip = clip
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region, space_data=area.spaces.active):
        assert bpy.ops.clip.solve_camera() == {"FINISHED"}


def test_non_joint_markers_become_static_tracks(empty_scene, tmp_path, filmed):
    import bpy

    from monoskel.blender import scene_data

    tracks, _ = filmed
    clip = _clip_with_markers(tmp_path, tracks)
    seen = [n for k, n in enumerate(tracks.static.names) if tracks.static.present[:, k].any()]
    clip.tracking.tracks[seen[0]].hide = True                # hidden: left out
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    got = scene_data.load_tracks(empty_scene)
    assert got.static is not None and got.static.names == tuple(seen[1:])
    k = tracks.static.names.index(seen[1])
    present = got.static.present[:, 0]
    np.testing.assert_allclose(got.static.xy[present, 0], tracks.static.xy[present, k], atol=1e-2)
    assert empty_scene.monoskel.tracks_static == len(seen) - 1


def test_blender_tripod_solve_is_read_and_compared(empty_scene, tmp_path, filmed):
    import bpy

    from monoskel.blender import movie_clip, scene_data
    from monoskel.core.evaluation.metrics import rotation_errors_deg

    tracks, truth = filmed
    clip = _clip_with_markers(tmp_path, tracks)
    assert movie_clip.blender_camera_solve(clip) is None      # nothing solved yet
    _tripod_solve(clip, 35.0)
    solve = movie_clip.blender_camera_solve(clip)
    assert solve is not None and solve["tripod"] and len(solve["frames"]) > N_FRAMES // 2
    # Blender's cameras, in our convention, against the truth (both relative to the first solved frame)
    f0 = solve["frames"][0]
    true_rel = np.array(truth.rotvec_deg)[solve["frames"]]
    from monoskel.core.camera import rotation_matrix, rotvec_deg

    R_true = rotation_matrix(true_rel) @ rotation_matrix(np.array(truth.rotvec_deg[f0])).T
    assert np.median(rotation_errors_deg(solve["rotvec_deg"], rotvec_deg(R_true))) < 0.3
    assert solve["focal_mm"] == pytest.approx(35.0, rel=1e-3)

    settings = empty_scene.monoskel
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    settings.estimate_focal = True                            # our own focal length from the background
    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    est = scene_data.load_estimate(empty_scene)
    sc = est.diagnostics["scene_camera"]
    assert sc["used"] and sc["points_used"] >= 8
    cmp = est.diagnostics["blender_solve"]
    assert cmp["frames"] == len(solve["frames"])
    assert cmp["rotation_deg_median"] < 0.3 and abs(cmp["focal_pct"]) < 3.0
    assert "Blender's camera solve" in settings.est_blender_solve and "Background:" in settings.est_scene_camera


def test_use_background_switch(empty_scene, tmp_path, filmed):
    import bpy

    from monoskel.blender import scene_data

    tracks, _ = filmed
    _clip_with_markers(tmp_path, tracks)
    settings = empty_scene.monoskel
    assert bpy.ops.monoskel.clip_to_tracks() == {"FINISHED"}
    settings.estimate_focal = True
    settings.use_background = False
    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    est = scene_data.load_estimate(empty_scene)
    assert "scene_camera" not in est.diagnostics and settings.est_scene_camera == ""
    assert scene_data.load_tracks(empty_scene).static is not None     # the scene keeps them
