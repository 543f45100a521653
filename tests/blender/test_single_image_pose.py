"""Pose from one image in Blender: the operator, the sidebar's toggles and scale, undo-safe errors."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def scene_with_tracks(empty_scene):
    from monoskel.blender import scene_data
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.operators.summary import set_tracks_summary

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=60), focal_mm=35.0, noise_px=0.0, seed=1)
    scene_data.store_tracks(empty_scene, tracks)
    set_tracks_summary(empty_scene.monoskel, tracks)
    empty_scene.monoskel.tracks_first_frame = 1
    empty_scene.frame_start, empty_scene.frame_end = 1, 60
    return empty_scene, tracks, truth


def _projected(scene, arm, cam, frame):
    """The armature's joints at ``frame`` seen through the camera, pixels (top-left origin, y down)."""
    import bpy
    from bpy_extras.object_utils import world_to_camera_view

    scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    from monoskel.blender.build_armature import BONES

    arm_eval = arm.evaluated_get(dg)
    pts = []
    for name, _, _, _ in BONES:
        p = arm_eval.matrix_world @ arm_eval.pose.bones[name].tail
        co = world_to_camera_view(scene, cam.evaluated_get(dg), p)
        pts.append((co.x * scene.render.resolution_x, (1 - co.y) * scene.render.resolution_y))
    return np.array(pts)


def test_pose_from_image_builds_a_posed_armature_and_a_camera_that_sees_it_on_the_joints(scene_with_tracks):
    import bpy

    from monoskel.blender.build_armature import BONES
    from monoskel.core.skeleton import JOINT_INDEX

    scene, tracks, _ = scene_with_tracks
    scene.frame_set(20)
    assert bpy.ops.monoskel.pose_from_image() == {"FINISHED"}
    s = scene.monoskel
    assert s.si_has_pose and s.si_frame == 20 and s.si_scale >= s.si_scale_min * 0.5
    arm, cam = s.si_armature, s.si_camera
    assert arm is not None and cam is not None and arm.type == "ARMATURE" and cam.type == "CAMERA"
    assert (scene.frame_start, scene.frame_end) == (1, 60)          # the clip's range is left alone
    scene.render.resolution_x, scene.render.resolution_y = (int(v) for v in tracks.image_size)
    got = _projected(scene, arm, cam, 20)
    want = np.array([tracks.xy[19, JOINT_INDEX[tail]] for _, _, tail, _ in BONES])
    assert np.median(np.linalg.norm(got - want, axis=1)) < 3.0      # the pose lands on the joints

    # a sign flip re-poses at once: the flipped segment's far joint moves in depth, the image stays
    before = np.array([arm.matrix_world @ pb.tail for pb in arm.pose.bones])
    k = 8
    was = s.si_signs[k]
    assert bpy.ops.monoskel.pose_flip_segment(index=k) == {"FINISHED"}
    assert s.si_signs[k] == (not was)
    scene.frame_set(20)
    after = np.array([arm.matrix_world @ pb.tail for pb in arm.pose.bones])
    assert np.max(np.linalg.norm(after - before, axis=1)) > 1e-3
    assert np.median(np.linalg.norm(_projected(scene, arm, cam, 20) - want, axis=1)) < 3.0
    # the scale cannot go below the smallest that fits; a larger one stretches the pose in depth (Taylor, fig. 4)
    assert bpy.ops.monoskel.pose_scale(scale=0.0) == {"FINISHED"}
    assert s.si_scale == pytest.approx(s.si_scale_min)
    depth = np.ptp([(arm.matrix_world @ pb.tail).y for pb in arm.pose.bones])
    assert bpy.ops.monoskel.pose_scale(scale=3 * s.si_scale_min) == {"FINISHED"}
    scene.frame_set(20)
    assert np.ptp([(arm.matrix_world @ pb.tail).y for pb in arm.pose.bones]) > depth   # more foreshortening

    # posing again replaces the objects in one step
    names = {o.name for o in bpy.data.objects}
    assert bpy.ops.monoskel.pose_from_image() == {"FINISHED"}
    assert {o.name for o in bpy.data.objects} == names


def test_frame_without_tracks_reports_and_changes_nothing(scene_with_tracks):
    import bpy

    scene, _, _ = scene_with_tracks
    scene.frame_set(200)
    before = set(bpy.data.objects.keys())
    with pytest.raises(RuntimeError, match="has no tracks"):
        bpy.ops.monoskel.pose_from_image()
    assert set(bpy.data.objects.keys()) == before and not scene.monoskel.si_has_pose


def test_sidebar_rows_show_one_toggle_per_segment(scene_with_tracks):
    import bpy

    from monoskel.core.single_image import SEGMENT_NAMES
    from monoskel.ui import state

    scene, _, _ = scene_with_tracks
    rows = state.section_rows("single_image", scene.monoskel)
    assert rows[0].op == "monoskel.pose_from_image" and rows[0].enabled
    scene.frame_set(5)
    bpy.ops.monoskel.pose_from_image()
    rows = state.section_rows("single_image", scene.monoskel)
    toggles = [r for r in rows if r.op == "monoskel.pose_flip_segment"]
    assert [r.text for r in toggles] == SEGMENT_NAMES
    assert [dict(r.op_props)["index"] for r in toggles] == list(range(16))
    assert [r.depress for r in toggles] == list(scene.monoskel.si_signs)
