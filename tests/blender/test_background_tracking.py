"""Track Background: Blender's detector and tracker find static scene features on a clip the test paints
with numpy (one textured patch per static scene point of a handheld shot, the person's joints drawn over
them), keep them off the person, and the camera solved with them is measured against the truth."""

from __future__ import annotations

import numpy as np
import pytest

N_FRAMES = 60


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    """(joint tracks without background, truth tracks with the static points, truth, folder of PNG frames)."""
    from monoskel.core.synthetic.footage_sim import HandheldOperator
    from monoskel.core.synthetic.footage_sim.painted import paint_frames, write_png_sequence
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    filmed, truth = synthesize(load_motion("builtin:walk", max_frames=N_FRAMES), kinds=(), focal_mm=35.0,
                               noise_px=0.0, seed=4, operator=HandheldOperator(moves_per_s=1.5), static_points=24)
    folder = tmp_path_factory.mktemp("painted_bg")
    # the scene's points first: the person's joints are drawn over them where they pass
    paths = np.concatenate([filmed.static.xy, filmed.xy], axis=1)
    write_png_sequence(paint_frames(paths, filmed.image_size, turn_deg_per_frame=0.0, seed=5,
                                    zoom=truth.focal_mm / truth.focal_mm[0]), folder, stem="shot")
    return filmed.replaced(static=None), filmed, truth, folder


def _load(scene, tmp_path, tracks, folder):
    import bpy

    from monoskel.core.tracks import write_tracks_json

    path = tmp_path / "joints.json"
    write_tracks_json(tracks, path)
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    clip = bpy.data.movieclips.load(str(folder / "shot_0001.png"))
    scene.active_clip = clip
    return clip


def test_background_features_are_found_off_the_person_and_follow_the_scene(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.background_tracking import BG_PREFIX
    from monoskel.core.evaluation.metrics import followed_point_errors_px

    joints, filmed, _, folder = footage
    clip = _load(empty_scene, tmp_path, joints, folder)
    mine = clip.tracking.tracks.new(name="floor mark", frame=1)      # the animator's own track
    mine.select = True
    empty_scene.frame_set(9)
    frames = (empty_scene.frame_start, empty_scene.frame_end)
    empty_scene.monoskel.use_background = False
    defaults = clip.tracking.settings
    before = (defaults.default_pattern_size, defaults.default_search_size, defaults.default_motion_model,
              defaults.default_pattern_match)

    assert bpy.ops.monoskel.track_background() == {"FINISHED"}

    tracks = scene_data.load_tracks(empty_scene)
    found = tracks.static
    assert found is not None and found.n_points >= 8, found
    np.testing.assert_allclose(tracks.xy, joints.xy, atol=1e-3)       # the joints are not touched
    live = found.present.sum(axis=1)
    assert np.median(live) >= 8 and live.min() >= 4, live
    # every kept feature sits on a painted scene point and moves with it (the camera's motion)
    gaps, errors = followed_point_errors_px(found.xy, filmed.static.xy)
    start_gap, motion_err = float(gaps.max()), float(errors.max())
    assert start_gap < 13.0, start_gap            # on its patch: a 17 px square's corner is 12 px from its centre
    assert motion_err < 1.5, motion_err
    # none on the person: no kept position inside the joints' own extent
    lo, hi = np.nanmin(joints.xy, axis=1), np.nanmax(joints.xy, axis=1)
    on_person = ((found.xy >= lo[:, None]) & (found.xy <= hi[:, None])).all(axis=-1)
    assert not on_person.any()
    # the clip shows them under their names; the animator's track, selection and the scene are as they were
    names = sorted(t.name for t in clip.tracking.tracks if t.name.startswith(BG_PREFIX))
    assert names == sorted(found.names)
    assert "floor mark" in [t.name for t in clip.tracking.tracks] and mine.select
    assert not any(t.name.startswith("MonoSkel new") for t in clip.tracking.tracks)
    assert (empty_scene.frame_start, empty_scene.frame_end, empty_scene.frame_current) == (*frames, 9)
    assert (defaults.default_pattern_size, defaults.default_search_size, defaults.default_motion_model,
            defaults.default_pattern_match) == before
    assert empty_scene.monoskel.use_background and empty_scene.monoskel.tracks_static == found.n_points


def test_the_camera_from_the_tracked_background_beats_the_person_alone(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.estimate import estimate
    from monoskel.core.evaluation.evaluate import score

    joints, _, truth, folder = footage
    _load(empty_scene, tmp_path, joints, folder)
    assert bpy.ops.monoskel.track_background() == {"FINISHED"}
    tracks = scene_data.load_tracks(empty_scene)
    with_scene = score(estimate(tracks, "joint"), truth)["rotation_error_deg"]
    alone = score(estimate(joints, "joint"), truth)["rotation_error_deg"]
    assert with_scene < 0.5 and with_scene < 0.5 * alone, (with_scene, alone)


def test_a_second_run_replaces_the_first_and_a_failed_run_changes_nothing(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.background_tracking import BG_PREFIX
    from monoskel.core.tracks import tracks_to_dict

    joints, _, _, folder = footage
    clip = _load(empty_scene, tmp_path, joints, folder)
    assert bpy.ops.monoskel.track_background(want=8) == {"FINISHED"}
    first = sorted(t.name for t in clip.tracking.tracks)
    bpy.ops.ed.undo_push(message="first background")
    assert bpy.ops.monoskel.track_background(want=10) == {"FINISHED"}
    ours = [t.name for t in clip.tracking.tracks if t.name.startswith(BG_PREFIX)]
    assert sorted(ours) == sorted(scene_data.load_tracks(empty_scene).static.names)
    # undo brings the first run's tracks back, on the clip and on the scene
    second, name = sorted(ours), clip.name
    bpy.ops.ed.undo_push(message="second background")
    bpy.ops.ed.undo()
    clip = bpy.data.movieclips[name]
    empty_scene = bpy.context.scene
    assert sorted(t.name for t in clip.tracking.tracks) == first != second
    assert sorted(scene_data.load_tracks(empty_scene).static.names) == [n for n in first if n.startswith(BG_PREFIX)]

    # tracks of another picture: refused, the clip's tracks and the scene's tracks untouched
    before_clip = sorted(t.name for t in clip.tracking.tracks)
    other = joints.replaced(xy=joints.xy * 0.5, image_size=(360.0, 300.0))
    scene_data.store_tracks(empty_scene, other)
    stored = tracks_to_dict(scene_data.load_tracks(empty_scene))
    with pytest.raises(RuntimeError, match="not the same picture"):
        bpy.ops.monoskel.track_background()
    assert sorted(t.name for t in clip.tracking.tracks) == before_clip
    assert tracks_to_dict(scene_data.load_tracks(empty_scene)) == stored
    # tracks detected on every other frame do not follow the clip frame by frame: refused too
    sparse = joints.frames_between(0, 29).replaced(meta={**joints.meta, "step": 2})
    scene_data.store_tracks(empty_scene, sparse)
    with pytest.raises(RuntimeError, match="one frame in 2"):
        bpy.ops.monoskel.track_background()
    assert sorted(t.name for t in clip.tracking.tracks) == before_clip


def test_the_headless_batch_tracks_the_background_of_a_tracks_files_footage(blender, tmp_path, footage):
    import json
    import subprocess
    import sys
    from pathlib import Path

    import bpy

    from monoskel.blender.background_tracking import BG_PREFIX
    from monoskel.core.tracks import write_tracks_json

    joints, _, _, folder = footage
    write_tracks_json(joints, tmp_path / "joints.json")
    batch = Path(__file__).resolve().parents[2] / "batch.py"

    def run(*args):
        return subprocess.run([sys.executable, str(batch), *map(str, args)], capture_output=True, text=True,
                              timeout=300)

    blend, result = tmp_path / "shot.blend", tmp_path / "shot.json"
    proc = run(tmp_path / "joints.json", "--footage", folder / "shot_0001.png", "--track-background",
               "--output", blend, "--result", result, "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert "background tracks" in proc.stderr and "in view on the median frame" in proc.stderr
    scene_camera = json.loads(result.read_text())["diagnostics"]["scene_camera"]
    assert scene_camera["used"] and scene_camera["points"] >= 8
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    try:
        clip = bpy.context.scene.active_clip
        assert clip is not None
        assert sum(t.name.startswith(BG_PREFIX) for t in clip.tracking.tracks) == scene_camera["points"]
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    # without footage there is nothing to follow: refused before anything is written
    proc = run(tmp_path / "joints.json", "--track-background", "--output", tmp_path / "x.blend")
    assert proc.returncode == 2 and "--footage" in proc.stderr and not (tmp_path / "x.blend").exists()
    proc = run("--video", folder / "shot_0001.png", "--detect-step", "2", "--track-background",
               "--output", tmp_path / "x.blend")
    assert proc.returncode == 2 and "--detect-step" in proc.stderr and not (tmp_path / "x.blend").exists()
