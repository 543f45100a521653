"""Refine Tracks on Footage: Blender's own tracker re-finds the detector's joints on a clip
the test paints with numpy (one textured patch per joint, moving along the joints' true image paths),
and the refined tracks are measured against that truth."""

from __future__ import annotations

import numpy as np
import pytest

N_FRAMES = 40
OUTLIERS = ((12, 4), (13, 4), (30, 10))          # (frame, joint) thrown 25 px off
GAP = (20, 21)                                    # the detector missed the head on these frames


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    """(truth tracks, detector tracks, folder of PNG frames): a 35 mm walk, 720x480, 2 px detector noise."""
    from monoskel.core.skeleton import JOINT_INDEX
    from monoskel.core.synthetic.footage_sim.painted import paint_frames, write_png_sequence
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    truth, _ = synthesize(load_motion("builtin:walk", max_frames=N_FRAMES), kinds=(), focal_mm=35.0,
                          noise_px=0.0, seed=11)
    folder = tmp_path_factory.mktemp("painted")
    write_png_sequence(paint_frames(truth.xy, truth.image_size, seed=2), folder, stem="walk")
    rng = np.random.default_rng(3)
    xy = truth.xy + rng.normal(0.0, 2.0, truth.xy.shape)
    conf = np.ones(truth.conf.shape)
    for f, j in OUTLIERS:
        xy[f, j] += (25.0, -18.0)
    head = JOINT_INDEX["head"]
    xy[list(GAP), head] = np.nan
    conf[list(GAP), head] = 0.0
    return truth, truth.replaced(xy=xy, conf=conf, source="detector"), folder


def _load(scene, tmp_path, detector, folder, frame_start=1):
    import bpy

    from monoskel.core.tracks import write_tracks_json

    path = tmp_path / "detector.json"
    write_tracks_json(detector, path)
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    clip = bpy.data.movieclips.load(str(folder / "walk_0001.png"))
    clip.frame_start = frame_start
    scene.active_clip = clip
    return clip


def _rms(xy, truth, mask):
    return float(np.sqrt(np.mean(np.sum((xy - truth) ** 2, axis=-1)[mask])))


def test_refined_tracks_are_nearer_the_truth(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.track_refinement.tracker import TEMP_PREFIX
    from monoskel.core.skeleton import JOINT_INDEX

    truth, detector, folder = footage
    clip = _load(empty_scene, tmp_path, detector, folder)
    mine = clip.tracking.tracks.new(name="floor mark", frame=1)    # the animator's own track
    mine.select = True
    empty_scene.frame_set(7)
    frames = (empty_scene.frame_start, empty_scene.frame_end)

    assert bpy.ops.monoskel.refine_tracks() == {"FINISHED"}

    refined = scene_data.load_tracks(empty_scene)
    good = detector.present.copy()
    for f, j in OUTLIERS:
        good[f, j] = False
    before, after = _rms(detector.xy, truth.xy, good), _rms(refined.xy, truth.xy, good)
    assert after < 0.7 * before, (before, after)          # measured 2.8 -> 1.3 px on this clip
    head = JOINT_INDEX["head"]
    assert refined.present[list(GAP), head].all()          # the tracker bridged the detector's gap
    assert np.abs(refined.xy[list(GAP), head] - truth.xy[list(GAP), head]).max() < 3.0
    np.testing.assert_array_equal(refined.conf[list(GAP), head], 0.5)
    info = refined.meta["refined"]
    assert info["clip"] == clip.name and info["window"] == 5 and info["refined_entries"] > 0.9 * good.sum()
    # the outliers disagreed and were left to the track cleaning (the default)
    for f, j in OUTLIERS:
        np.testing.assert_allclose(refined.xy[f, j], detector.xy[f, j], atol=1e-3)   # stored to 4 places
    assert info["disagreeing_entries"] >= len(OUTLIERS)
    # the clip and the scene are as they were: no temporary track, the animator's track and selection
    assert [t.name for t in clip.tracking.tracks] == ["floor mark"] and mine.select
    assert not any(t.name.startswith(TEMP_PREFIX) for t in clip.tracking.tracks)
    assert (empty_scene.frame_start, empty_scene.frame_end, empty_scene.frame_current) == (*frames, 7)
    assert not empty_scene.monoskel.has_estimate


def test_disagreeing_positions_can_follow_the_tracker(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data

    truth, detector, folder = footage
    _load(empty_scene, tmp_path, detector, folder)
    assert bpy.ops.monoskel.refine_tracks(disagree="REFINED", window=4) == {"FINISHED"}
    refined = scene_data.load_tracks(empty_scene)
    miss = [float(np.linalg.norm(refined.xy[f, j] - truth.xy[f, j])) for f, j in OUTLIERS]
    assert max(miss) < 8.0, miss                           # the detector put them 31 px off
    assert refined.meta["refined"]["window"] == 4


def test_tracks_of_another_picture_or_range_are_refused(empty_scene, tmp_path, footage):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.tracks import tracks_to_dict

    truth, detector, folder = footage
    half = detector.replaced(xy=detector.xy * 0.5, image_size=(360.0, 300.0))    # another aspect ratio
    clip = _load(empty_scene, tmp_path, half, folder)
    stored = tracks_to_dict(scene_data.load_tracks(empty_scene))
    with pytest.raises(RuntimeError, match="not the same picture"):
        bpy.ops.monoskel.refine_tracks()
    assert tracks_to_dict(scene_data.load_tracks(empty_scene)) == stored
    assert len(clip.tracking.tracks) == 0

    _load(empty_scene, tmp_path, detector, folder, frame_start=5)   # clip frame 1 shown at scene frame 5
    with pytest.raises(RuntimeError, match="not tracks of this clip"):
        bpy.ops.monoskel.refine_tracks()


def test_half_resolution_tracks_and_undo(empty_scene, tmp_path, footage):
    """Tracks from a detector run on a half-size copy of the footage are refined in their own pixels;
    one undo brings the detector's tracks back."""
    import bpy

    from monoskel.blender import scene_data

    truth, detector, folder = footage
    half = detector.replaced(xy=detector.xy * 0.5, image_size=(360.0, 240.0))
    _load(empty_scene, tmp_path, half, folder)
    bpy.ops.ed.undo_push(message="before refine")
    assert bpy.ops.monoskel.refine_tracks() == {"FINISHED"}
    refined = scene_data.load_tracks(empty_scene)
    assert refined.image_size == (360.0, 240.0)
    good = detector.present
    assert _rms(refined.xy, truth.xy * 0.5, good) < 0.8 * _rms(half.xy, truth.xy * 0.5, good)
    bpy.ops.ed.undo_push(message="refined")
    bpy.ops.ed.undo()
    back = scene_data.load_tracks(bpy.context.scene)
    assert "refined" not in back.meta
    np.testing.assert_allclose(back.xy[back.present], half.xy[half.present], atol=1e-3)
