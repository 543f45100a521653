"""Tracks, estimate and truth stored with the scene survive a round trip, a save and a reopen."""

import bpy
import numpy as np
import pytest


def _tracks():
    from monoskel.core.tracks import Tracks

    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 700, size=(5, 17, 2))
    conf = rng.uniform(0.2, 1.0, size=(5, 17))
    conf[2, 4] = 0.0
    return Tracks(xy, conf, 29.97, (720, 480), source="clip.json", meta={"camera": "phone"})


def _estimate():
    from monoskel.core.result import Estimate, FrameEstimate
    from monoskel.core.skeleton import CLASSES

    frames = [FrameEstimate(stance="l", rotvec_deg=(0.0, float(i), 0.0), focal_mm=40.0 + i,
                            joints_3d=[[0.1 * j, 0.2, 4.0 + i] for j in range(17)]) for i in range(5)]
    return Estimate("paper", {c: 0.1 for c in CLASSES}, 42.0, frames, height_m=1.7, diagnostics={"spells": []})


def test_nothing_stored_reads_as_none(empty_scene):
    from monoskel.blender import scene_data

    assert scene_data.load_tracks(empty_scene) is None
    assert scene_data.load_estimate(empty_scene) is None
    assert scene_data.load_truth(empty_scene) is None


def test_round_trip_in_hidden_texts_survives_save_and_reopen(empty_scene, tmp_path):
    from monoskel.blender import scene_data
    from monoskel.core.result import estimate_to_dict

    tracks, est = _tracks(), _estimate()
    scene_data.store_tracks(empty_scene, tracks)
    scene_data.store_estimate(empty_scene, est)
    scene_data.store_estimate(empty_scene, est)  # storing again replaces, never duplicates
    assert len(bpy.data.texts) == 2 and all(t.name.startswith(".") for t in bpy.data.texts)
    path = str(tmp_path / "stored.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    back = scene_data.load_tracks(scene)
    assert np.array_equal(back.present, tracks.present)
    assert np.allclose(back.xy[back.present], tracks.xy[tracks.present], atol=1e-4)
    assert (back.fps, back.image_size, back.source, back.meta) == (29.97, (720.0, 480.0), "clip.json",
                                                                    {"camera": "phone"})
    assert estimate_to_dict(scene_data.load_estimate(scene)) == estimate_to_dict(est)


def test_each_scene_keeps_its_own_data(empty_scene):
    from monoskel.blender import scene_data

    other = bpy.data.scenes.new("Other")
    scene_data.store_estimate(empty_scene, _estimate())
    assert scene_data.load_estimate(other) is None
    scene_data.clear(empty_scene, "estimate")
    assert scene_data.load_estimate(empty_scene) is None and len(bpy.data.texts) == 0


def test_truth_round_trip(empty_scene):
    from monoskel.blender import scene_data
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    _, truth = synthesize(load_motion("builtin:walk", max_frames=12), seed=2)
    scene_data.store_truth(empty_scene, truth)
    back = scene_data.load_truth(empty_scene)
    assert back.n_frames == 12
    assert np.allclose(back.joints_3d, truth.joints_3d, atol=1e-5)
    assert np.allclose(back.world_from_cam0, truth.world_from_cam0, atol=1e-8)
    assert back.proportions == pytest.approx(truth.proportions, abs=1e-7)
