"""Flip Bone Depth: a limb turned to its other side in depth over frames, the take's armature keyed again."""

from __future__ import annotations

import numpy as np
import pytest

HEIGHT = 1.7


def _built_scene(n_frames=16):
    """A walk's truth stored as the estimate (panning, zooming camera) and built into a take."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan", "zoom"), seed=2)
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    scene_data.store_estimate(scene, truth_as_estimate(truth))
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    scene.monoskel.height_m = HEIGHT
    assert bpy.ops.monoskel.build_armature() == {"FINISHED"}
    return scene


def _posed_wrist(scene, frame):
    scene.frame_set(frame)
    arm = scene.monoskel.armature
    return np.array(arm.matrix_world @ arm.pose.bones["forearm.L"].tail)


def test_flip_moves_the_wrist_on_its_frames_alone_and_builds_the_takes_armature_again(empty_scene):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.build import world_joints
    from monoskel.core.skeleton import JOINT_INDEX

    scene = _built_scene()
    first = scene.monoskel.tracks_first_frame
    name, objects = scene.monoskel.armature.name, len(bpy.data.objects)
    before = {f: _posed_wrist(scene, first + f) for f in range(16)}
    wrist = JOINT_INDEX["l_wrist"]
    old = np.array([fr.joints_3d for fr in scene_data.load_estimate(scene).frames])[:, wrist]
    assert bpy.ops.monoskel.flip_bone_depth(bone="l_wrist", frame_start=first + 3, frame_end=first + 8) == {"FINISHED"}
    # the active take's armature built again in its place (as Build Armature does), no second one
    assert scene.monoskel.armature.name == name and len(bpy.data.objects) == objects
    est = scene_data.load_estimate(scene)
    assert est.diagnostics["depth_flips"][-1]["first"] == 3 and est.diagnostics["depth_flips"][-1]["last"] == 8
    new = np.array([fr.joints_3d for fr in est.frames])[:, wrist]
    f = 3 + int(np.argmax(np.linalg.norm(new - old, axis=1)[3:9]))      # where the forearm slants most
    idx, joints = world_joints(est, HEIGHT)
    moved = _posed_wrist(scene, first + f)
    np.testing.assert_allclose(moved, joints[list(idx).index(f), wrist], atol=2e-3)
    assert np.linalg.norm(moved - before[f]) > 0.05
    for f in (0, 1, 2, 9, 12, 15):
        np.testing.assert_allclose(_posed_wrist(scene, first + f), before[f], atol=1e-4)


def test_flip_outside_the_clip_fails_in_one_line_and_changes_nothing(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene = _built_scene()
    text = scene_data.load_estimate(scene).frames[3].joints_3d
    with pytest.raises(RuntimeError, match="not in the estimate") as info:
        bpy.ops.monoskel.flip_bone_depth(bone="r_ankle", frame_start=500, frame_end=510)
    assert "Traceback" not in str(info.value)
    assert scene_data.load_estimate(scene).frames[3].joints_3d == text


def test_undo_takes_the_flip_back(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene = _built_scene()
    first = scene.monoskel.tracks_first_frame
    before = scene_data.load_estimate(scene).frames[4].joints_3d
    wrist = _posed_wrist(scene, first + 4)
    bpy.ops.ed.undo_push(message="before the flip")
    assert bpy.ops.monoskel.flip_bone_depth(bone="l_wrist", frame_start=first, frame_end=first + 10) == {"FINISHED"}
    bpy.ops.ed.undo_push(message="flipped")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert scene_data.load_estimate(scene).frames[4].joints_3d == before
    np.testing.assert_allclose(_posed_wrist(scene, first + 4), wrist, atol=1e-4)


def test_the_results_section_offers_the_flip_once_there_is_motion(empty_scene):
    import bpy

    from monoskel.ui import state

    assert "UNDO" in bpy.types.MONOSKEL_OT_flip_bone_depth.bl_options
    scene = _built_scene(n_frames=6)
    rows = [r for r in state.section_rows("results", scene.monoskel) if r.op == "monoskel.flip_bone_depth"]
    assert len(rows) == 1 and rows[0].enabled
    scene.monoskel.est_has_motion = False
    assert not [r for r in state.section_rows("results", scene.monoskel) if r.op == "monoskel.flip_bone_depth"]


def test_frames_not_given_are_the_current_one(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene = _built_scene(n_frames=10)
    first = scene.monoskel.tracks_first_frame
    scene.frame_set(first + 6)
    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(rig)
    scene.monoskel.retarget_target = rig                  # the report then says to retarget again
    assert bpy.ops.monoskel.flip_bone_depth(bone="r_wrist") == {"FINISHED"}
    assert bpy.ops.monoskel.flip_bone_depth(bone="l_knee", frame_start=first + 2) == {"FINISHED"}
    flips = [(f["bone"], f["first"], f["last"]) for f in scene_data.load_estimate(scene).diagnostics["depth_flips"]]
    assert flips == [("r_wrist", 6, 6), ("l_knee", 2, 2)]


def test_pose_modes_right_click_menu_offers_flip_and_plant_on_the_estimates_armature(empty_scene):
    import bpy

    from monoskel.operators import review

    menu = bpy.types.VIEW3D_MT_pose_context_menu
    assert review.menu_func_pose in menu.draw._draw_funcs

    class Layout:
        def __init__(self):
            self.ops = []

        def separator(self):
            pass

        def operator(self, idname, text=""):
            self.ops.append(idname)

    class Context:
        def __init__(self, scene, obj):
            self.scene, self.object = scene, obj

    scene = _built_scene(n_frames=4)
    for obj, shown in ((scene.monoskel.armature, True), (None, False)):
        holder = type("Menu", (), {"layout": Layout()})()
        review.menu_func_pose(holder, Context(scene, obj))
        assert holder.layout.ops == (["monoskel.flip_bone_depth", "monoskel.plant_foot"] if shown else [])
