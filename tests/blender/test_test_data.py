"""Make Test Data: a known motion filmed by the virtual camera, its tracks, truth and truth armature."""

from __future__ import annotations

import numpy as np
import pytest


def test_builtin_walk_makes_tracks_truth_and_truth_armature(empty_scene):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.skeleton import CLASSES
    from monoskel.core.synthetic.motion import load_motion

    s = empty_scene.monoskel
    s.test_source = "builtin:walk"
    s.test_kinds = {"still", "pan"}
    s.test_noise_px, s.test_dropout, s.test_seed, s.test_max_frames = 0.5, 0.1, 4, 40

    assert bpy.ops.monoskel.import_test_data() == {"FINISHED"}

    tracks = scene_data.load_tracks(empty_scene)
    truth = scene_data.load_truth(empty_scene)
    assert tracks.n_frames == 40 and truth.n_frames == 40
    assert tracks.missing_fraction() == pytest.approx(0.1, abs=0.03)
    assert {sp.kind for sp in truth.spells} <= {"still", "pan"}
    motion = load_motion("builtin:walk", height_m=s.height_m, max_frames=40)
    np.testing.assert_allclose(truth.proportions, motion.proportions, rtol=1e-9)
    # The summary the Results panel compares against.
    assert s.has_tracks and s.has_truth and not s.has_estimate
    np.testing.assert_allclose(list(s.truth_proportions), truth.proportions, rtol=1e-5)
    assert s.truth_focal_mm == pytest.approx(float(np.mean(truth.focal_mm)), rel=1e-5)
    # The truth armature: the estimate's own rig, animated over the clip.
    arm = s.truth_armature
    assert arm is not None and arm.type == "ARMATURE" and len(arm.data.bones) == 16
    assert arm.animation_data is not None and arm.animation_data.action is not None
    assert empty_scene.frame_start == 1 and empty_scene.frame_end == 40
    assert len(CLASSES) == len(s.truth_proportions)


def test_same_seed_gives_the_same_tracks(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    s = empty_scene.monoskel
    s.test_max_frames, s.test_seed, s.test_noise_px = 20, 7, 2.0
    bpy.ops.monoskel.import_test_data()
    first = scene_data.load_tracks(empty_scene).xy.copy()
    bpy.ops.monoskel.import_test_data()
    np.testing.assert_allclose(scene_data.load_tracks(empty_scene).xy, first, equal_nan=True, atol=1e-3)
    s.test_seed = 8
    bpy.ops.monoskel.import_test_data()
    assert not np.allclose(scene_data.load_tracks(empty_scene).xy, first, equal_nan=True, atol=1e-3)


def test_missing_bvh_file_reports_and_creates_nothing(empty_scene, tmp_path):
    import bpy

    s = empty_scene.monoskel
    s.test_source = "FILE"
    with pytest.raises(RuntimeError, match="Choose a BVH file first"):
        bpy.ops.monoskel.import_test_data()
    s.test_bvh_path = str(tmp_path / "nope.bvh")
    with pytest.raises(RuntimeError, match="no such BVH file"):
        bpy.ops.monoskel.import_test_data()
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n")
    s.test_bvh_path = str(bad)
    with pytest.raises(RuntimeError, match="bad.bvh"):
        bpy.ops.monoskel.import_test_data()
    assert len(bpy.data.objects) == 0 and len(bpy.data.texts) == 0 and not s.has_tracks


def test_bvh_file_uses_blenders_importer_at_the_truth_scale(empty_scene, shared_bvh_dir):
    import bpy

    from monoskel.blender import scene_data

    path = shared_bvh_dir / "bandai_dataset-1_walk-left_normal_001.bvh"
    s = empty_scene.monoskel
    s.test_source, s.test_bvh_path, s.test_max_frames = "FILE", str(path), 30
    assert bpy.ops.monoskel.import_test_data() == {"FINISHED"}
    truth = scene_data.load_truth(empty_scene)
    arm = s.truth_armature
    assert arm is not None and arm.type == "ARMATURE"
    # Blender's importer keeps the file's bone names (the canonical rig would have "thigh.L").
    assert "thigh.L" not in arm.data.bones and len(arm.data.bones) > 16
    # Scaled like the core's figure: the armature's vertical extent at frame 1 is about the standing height.
    empty_scene.frame_set(1)
    z = [(arm.matrix_world @ b.head).z for b in arm.pose.bones] + [(arm.matrix_world @ b.tail).z
                                                                  for b in arm.pose.bones]
    assert 0.7 * truth.height_m < max(z) - min(z) < 1.2 * truth.height_m
    assert scene_data.load_tracks(empty_scene).n_frames == 30
