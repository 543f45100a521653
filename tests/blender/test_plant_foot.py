"""Plant Foot: a sliding foot held still over frames, the take's armature keyed again."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

HEIGHT = 1.7


def _built_scene(n_frames=40):
    """A walk's truth, its left ankle sliding in depth from frame 10 on, stored as the estimate and built into
    a take; and the left foot's contact in it (0-based frames)."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.motion_cleanup.foot_lock import LEGS, two_bone_ik
    from monoskel.core.runs import runs
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan",), seed=2)
    est = truth_as_estimate(truth)
    j = np.array([fr.joints_3d for fr in est.frames])
    hip, knee, ankle = LEGS[0]
    t = np.clip(np.arange(n_frames) - 10, 0, None)[:, None] / truth.fps
    ray = j[:, ankle] / np.linalg.norm(j[:, ankle], axis=1, keepdims=True)
    j[:, knee], j[:, ankle] = two_bone_ik(j[:, hip], j[:, knee], j[:, ankle], j[:, ankle] + 0.3 * t * ray)
    est = dataclasses.replace(est, frames=[dataclasses.replace(fr, joints_3d=p.tolist())
                                           for fr, p in zip(est.frames, j, strict=True)])
    contact = next((int(a), int(b) - 1) for a, b in runs([s == "l" for s in truth.stance]) if b - a >= 6 and a >= 10)
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    scene.monoskel.height_m = HEIGHT
    assert bpy.ops.monoskel.build_armature() == {"FINISHED"}
    return scene, contact


def _posed_ankle(scene, frame):
    scene.frame_set(frame)
    arm = scene.monoskel.armature
    return np.array(arm.matrix_world @ arm.pose.bones["shin.L"].tail)


def test_plant_holds_the_ankle_on_its_frames_and_builds_the_takes_armature_again(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, (a, b) = _built_scene()
    first = scene.monoskel.tracks_first_frame
    name, objects = scene.monoskel.armature.name, len(bpy.data.objects)
    before = [_posed_ankle(scene, first + f) for f in range(a, b + 1)]
    early = _posed_ankle(scene, first + 2)
    assert bpy.ops.monoskel.plant_foot(foot="l", frame_start=first + a, frame_end=first + b) == {"FINISHED"}
    assert scene.monoskel.armature.name == name and len(bpy.data.objects) == objects
    report = scene_data.load_estimate(scene).diagnostics["planted_feet"][-1]
    assert (report["foot"], report["first"], report["last"]) == ("l", a, b)
    after = np.array([_posed_ankle(scene, first + f) for f in range(a, b + 1)])
    spread = np.linalg.norm(after - np.median(after, axis=0), axis=1)
    slid = np.linalg.norm(np.array(before) - np.median(before, axis=0), axis=1)
    assert slid.max() > 0.02 and np.median(spread) < 2e-3          # the rig's ankle stands where it slid
    np.testing.assert_allclose(_posed_ankle(scene, first + 2), early, atol=1e-4)       # far from the span: as it was


def test_frames_not_given_are_where_the_foot_stands_around_the_current_one(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, (a, b) = _built_scene()
    first = scene.monoskel.tracks_first_frame
    scene.frame_set(first + (a + b) // 2)
    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(rig)
    scene.monoskel.retarget_target = rig                  # the report then says to retarget again
    assert bpy.ops.monoskel.plant_foot(foot="l") == {"FINISHED"}
    report = scene_data.load_estimate(scene).diagnostics["planted_feet"][-1]
    assert report["first"] <= (a + b) // 2 <= report["last"] and abs(report["first"] - a) <= 3


def test_plant_outside_the_clip_fails_in_one_line_and_changes_nothing(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, _ = _built_scene()
    text = scene_data.load_estimate(scene).frames[3].joints_3d
    with pytest.raises(RuntimeError, match="not in the estimate") as info:
        bpy.ops.monoskel.plant_foot(foot="r", frame_start=500, frame_end=510)
    assert "Traceback" not in str(info.value)
    assert scene_data.load_estimate(scene).frames[3].joints_3d == text


def test_undo_takes_the_plant_back(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, (a, b) = _built_scene()
    first = scene.monoskel.tracks_first_frame
    before = scene_data.load_estimate(scene).frames[b].joints_3d
    ankle = _posed_ankle(scene, first + b)
    bpy.ops.ed.undo_push(message="before the plant")
    assert bpy.ops.monoskel.plant_foot(foot="l", frame_start=first + a, frame_end=first + b) == {"FINISHED"}
    bpy.ops.ed.undo_push(message="planted")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert scene_data.load_estimate(scene).frames[b].joints_3d == before
    np.testing.assert_allclose(_posed_ankle(scene, first + b), ankle, atol=1e-4)


def test_the_results_section_offers_it_once_there_is_motion(empty_scene):
    import bpy

    from monoskel.ui import state

    assert "UNDO" in bpy.types.MONOSKEL_OT_plant_foot.bl_options
    scene, _ = _built_scene()
    rows = [r for r in state.section_rows("results", scene.monoskel) if r.op == "monoskel.plant_foot"]
    assert len(rows) == 1 and rows[0].enabled
    scene.monoskel.est_has_motion = False
    assert not [r for r in state.section_rows("results", scene.monoskel) if r.op == "monoskel.plant_foot"]
