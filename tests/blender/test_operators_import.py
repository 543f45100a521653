"""Import Tracks operator on real files: native JSON, a CSV format, bad files."""

from __future__ import annotations

import numpy as np
import pytest


def _walk_tracks(n_frames=24, dropout=0.1):
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    motion = load_motion("builtin:walk", max_frames=n_frames)
    tracks, _ = synthesize(motion, kinds=("pan",), noise_px=0.5, dropout=dropout, seed=3)
    return tracks


def _scene_counts():
    import bpy

    return {"objects": len(bpy.data.objects), "texts": len(bpy.data.texts), "actions": len(bpy.data.actions)}


def test_import_native_json_stores_tracks_and_sets_scene(empty_scene, tmp_path, capfd):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.tracks import write_tracks_json

    tracks = _walk_tracks()
    path = tmp_path / "walk.json"
    write_tracks_json(tracks, path)

    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    # The report (printed by Blender in background mode) summarises what came in.
    out = capfd.readouterr().out
    missing = f"{100 * tracks.missing_fraction():.1f}% missing"
    present = int(tracks.present.any(axis=0).sum())
    assert f"walk.json: {tracks.n_frames} frames at 30 fps, {present}/17 joints present, {missing}" in out

    scene = bpy.context.scene
    stored = scene_data.load_tracks(scene)
    assert stored is not None and stored.n_frames == tracks.n_frames
    np.testing.assert_allclose(stored.xy, tracks.xy, atol=1e-3, equal_nan=True)
    s = scene.monoskel
    assert s.has_tracks and s.tracks_frames == tracks.n_frames
    assert s.tracks_fps == pytest.approx(tracks.fps)
    assert (s.tracks_width, s.tracks_height) == tuple(int(v) for v in tracks.image_size)
    assert s.tracks_missing == pytest.approx(tracks.missing_fraction(), abs=1e-6)
    assert s.tracks_joints_present == int(tracks.present.any(axis=0).sum())
    assert scene.frame_end - scene.frame_start + 1 == tracks.n_frames
    assert scene.render.fps / scene.render.fps_base == pytest.approx(tracks.fps)
    assert (scene.render.resolution_x, scene.render.resolution_y) == (s.tracks_width, s.tracks_height)


def test_import_generic_csv_uses_given_fps_and_size(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.io.formats import write_generic_csv

    tracks = _walk_tracks(n_frames=12, dropout=0.0)
    path = tmp_path / "walk.csv"
    write_generic_csv(tracks, path)

    result = bpy.ops.monoskel.import_tracks(filepath=str(path), format="generic_csv", fps=25.0,
                                            width=640, height=360)
    assert result == {"FINISHED"}
    stored = scene_data.load_tracks(bpy.context.scene)
    assert stored.fps == pytest.approx(25.0)
    assert stored.image_size == (640.0, 360.0)
    assert stored.n_frames == tracks.n_frames
    # The operator's options become the sidebar's defaults for the next import.
    assert bpy.context.scene.monoskel.import_format == "generic_csv"
    assert bpy.context.scene.render.fps == 25


def test_import_falls_back_to_scene_fps_only_when_the_file_lacks_it(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.io.formats import write_generic_csv

    tracks = _walk_tracks(n_frames=8, dropout=0.0)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.render.resolution_x, scene.render.resolution_y = 800, 600

    # With its "# fps" / "# image_size" comment lines the file's own values win over the scene's.
    with_header = tmp_path / "with_header.csv"
    write_generic_csv(tracks, with_header)
    assert bpy.ops.monoskel.import_tracks(filepath=str(with_header), format="generic_csv") == {"FINISHED"}
    stored = scene_data.load_tracks(scene)
    assert stored.fps == pytest.approx(tracks.fps) and stored.image_size == tracks.image_size

    # Without them the scene's frame rate and render size fill in.
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.render.resolution_x, scene.render.resolution_y = 800, 600
    bare = tmp_path / "bare.csv"
    bare.write_text("".join(line for line in with_header.read_text().splitlines(keepends=True)
                            if not line.startswith("#")))
    assert bpy.ops.monoskel.import_tracks(filepath=str(bare), format="generic_csv") == {"FINISHED"}
    stored = scene_data.load_tracks(scene)
    assert stored.fps == pytest.approx(24.0)
    assert stored.image_size == (800.0, 600.0)
    assert stored.n_frames == tracks.n_frames


def test_bad_file_reports_one_line_and_leaves_scene_unchanged(empty_scene, tmp_path):
    import bpy

    bad = tmp_path / "broken.json"
    bad.write_text('{"format": "skeleton-tracks", "version": 1, "fps": -3}')
    before = _scene_counts()
    with pytest.raises(RuntimeError) as info:
        bpy.ops.monoskel.import_tracks(filepath=str(bad), format="native")
    message = str(info.value).strip()
    assert "broken.json" in message and "fps" in message
    assert "Traceback" not in message and len(message.splitlines()) == 1
    assert _scene_counts() == before
    assert not bpy.context.scene.monoskel.has_tracks


def test_missing_file_and_garbage_file_fail_cleanly(empty_scene, tmp_path):
    import bpy

    with pytest.raises(RuntimeError, match="no such file"):
        bpy.ops.monoskel.import_tracks(filepath=str(tmp_path / "absent.json"))
    garbage = tmp_path / "garbage.json"
    garbage.write_bytes(b"\x00\x01 not json at all")
    with pytest.raises(RuntimeError, match="garbage.json"):
        bpy.ops.monoskel.import_tracks(filepath=str(garbage), format="native")
    assert len(bpy.data.texts) == 0 and not bpy.context.scene.monoskel.has_tracks


def test_reimport_replaces_tracks_and_forgets_the_old_estimate(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.test_data import truth_as_estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    motion = load_motion("builtin:walk", max_frames=10)
    tracks, truth = synthesize(motion, kinds=("still",), seed=0)
    path = tmp_path / "a.json"
    write_tracks_json(tracks, path)
    bpy.ops.monoskel.import_tracks(filepath=str(path))
    scene = bpy.context.scene
    scene_data.store_estimate(scene, truth_as_estimate(truth))
    bpy.ops.monoskel.refresh()
    assert scene.monoskel.has_estimate

    bpy.ops.monoskel.import_tracks(filepath=str(path))
    assert not scene.monoskel.has_estimate
    assert scene_data.load_estimate(scene) is None
    assert len([t for t in bpy.data.texts if "tracks" in t.name]) == 1


def test_import_declares_undo_and_register(blender):
    import bpy

    assert {"REGISTER", "UNDO"} <= set(bpy.types.MONOSKEL_OT_import_tracks.bl_options)


def test_undo_restores_the_scene_before_the_import(empty_scene, tmp_path):
    """Headless undo needs explicit steps (operators run from Python push none); then it works."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.tracks import write_tracks_json

    path = tmp_path / "walk.json"
    write_tracks_json(_walk_tracks(n_frames=9), path)
    bpy.ops.ed.undo_push(message="before import")
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    bpy.ops.ed.undo_push(message="after import")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert not scene.monoskel.has_tracks and scene_data.load_tracks(scene) is None
    assert len(bpy.data.texts) == 0
    bpy.ops.ed.redo()
    scene = bpy.context.scene
    assert scene.monoskel.tracks_frames == 9 and scene_data.load_tracks(scene).n_frames == 9


def test_import_openpose_folder_picks_the_directory(empty_scene, tmp_path):
    """A folder format: the file browser hands over a directory (or a file inside it)."""
    import json

    import bpy

    from monoskel.blender import scene_data

    folder = tmp_path / "openpose"
    folder.mkdir()
    rng = np.random.default_rng(0)
    for i in range(4):
        keypoints = []
        for _ in range(25):
            keypoints += [float(rng.uniform(100, 500)), float(rng.uniform(50, 400)), 0.9]
        (folder / f"clip_{i:012d}_keypoints.json").write_text(json.dumps({"people": [{"pose_keypoints_2d":
                                                                                       keypoints}]}))
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 25, 1.0
    result = bpy.ops.monoskel.import_tracks(directory=str(folder) + "/", filepath=str(folder) + "/",
                                            format="openpose", width=640, height=480)
    assert result == {"FINISHED"}
    tracks = scene_data.load_tracks(scene)
    assert tracks.n_frames == 4 and tracks.image_size == (640.0, 480.0)
    assert tracks.fps == pytest.approx(25.0)  # OpenPose stores no rate: the scene's is used

    # Picking one of the frame files with the folder format selected reads the whole folder too.
    result = bpy.ops.monoskel.import_tracks(filepath=str(folder / "clip_000000000002_keypoints.json"),
                                            format="openpose", fps=30.0, width=640, height=480)
    assert result == {"FINISHED"}
    assert scene_data.load_tracks(scene).n_frames == 4


def test_trim_keeps_the_scene_range_of_the_tracks_in_place_and_undoes(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.tracks import write_tracks_json

    tracks = _walk_tracks(n_frames=30)
    path = tmp_path / "walk.json"
    write_tracks_json(tracks, path)
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    scene = bpy.context.scene
    first = scene.monoskel.tracks_first_frame
    assert bpy.ops.monoskel.trim_tracks() == {"CANCELLED"}         # the range holds them all: nothing to do
    bpy.ops.ed.undo_push(message="before trim")
    scene.frame_start, scene.frame_end = first + 5, first + 19
    assert bpy.ops.monoskel.trim_tracks() == {"FINISHED"}
    kept = scene_data.load_tracks(scene)
    assert kept.n_frames == 15 and scene.monoskel.tracks_frames == 15
    assert np.allclose(kept.xy, tracks.xy[5:20], atol=1e-3, equal_nan=True)    # the file keeps 4 decimals
    assert scene.monoskel.tracks_first_frame == first + 5               # the stretch keeps its place in time
    assert (scene.frame_start, scene.frame_end) == (first + 5, first + 19)
    bpy.ops.ed.undo_push(message="after trim")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert scene_data.load_tracks(scene).n_frames == 30
    scene.frame_start, scene.frame_end = first + 40, first + 50          # past the tracks: one line, nothing changed
    with pytest.raises(RuntimeError, match="fewer than 2 of the tracks' frames"):
        bpy.ops.monoskel.trim_tracks()
    assert scene_data.load_tracks(scene).n_frames == 30
