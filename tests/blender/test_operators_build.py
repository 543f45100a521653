"""Build and Export operators: objects made from the stored estimate, failures, undo."""

from __future__ import annotations

import numpy as np
import pytest

HEIGHT = 1.62


def _scene_with_estimate(n_frames=20, tmp_path=None):
    """Tracks + an estimate on the scene (the truth of a synthetic walk, shaped as an estimate)."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.test_data import truth_as_estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    motion = load_motion("builtin:walk", max_frames=n_frames)
    tracks, truth = synthesize(motion, kinds=("pan", "zoom"), seed=2)
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    est = truth_as_estimate(truth)
    est.method = "test"
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    scene.monoskel.height_m = HEIGHT
    return scene, tracks, est


def _expected_bone_lengths(est, height):
    from monoskel.blender.build_armature import BONES
    from monoskel.core.skeleton import JOINT_INDEX, SEGMENT_CLASS, SEGMENTS, class_lengths_for_height

    lengths = class_lengths_for_height(est.proportions_vector(), height)
    class_of_child = {child: SEGMENT_CLASS[s] for s, (_, child) in enumerate(SEGMENTS)}
    return {name: lengths[class_of_child[JOINT_INDEX[tail]]] for name, _, tail, _ in BONES}


def test_build_armature_bone_lengths_are_proportions_at_the_subject_height(empty_scene):
    import bpy

    scene, _, est = _scene_with_estimate()
    assert bpy.ops.monoskel.build_armature() == {"FINISHED"}
    arm = scene.monoskel.armature
    assert arm is not None and arm.type == "ARMATURE"
    expected = _expected_bone_lengths(est, HEIGHT)
    got = {b.name: b.length for b in arm.data.bones}
    assert set(got) == set(expected) and len(got) == 16
    for name, length in expected.items():
        assert got[name] == pytest.approx(length, rel=1e-4), name
    assert arm.animation_data is not None and arm.animation_data.action is not None


def test_build_camera_respects_the_tracks_view_toggle(empty_scene):
    import bpy

    scene, _, est = _scene_with_estimate()
    scene.monoskel.build_tracks_view = False
    assert bpy.ops.monoskel.build_camera() == {"FINISHED"}
    cam = scene.monoskel.camera
    assert cam is not None and cam.type == "CAMERA" and scene.camera == cam
    assert cam.data.sensor_width == pytest.approx(36.0)
    assert list(cam.children) == []

    scene.monoskel.build_tracks_view = True
    assert bpy.ops.monoskel.build_camera() == {"FINISHED"}
    assert len(scene.monoskel.camera.children) >= 1


def test_build_all_follows_the_toggles(empty_scene):
    import bpy

    scene, _, _ = _scene_with_estimate()
    s = scene.monoskel
    s.build_camera = False
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert s.armature is not None and s.camera is None
    assert not any(o.type == "CAMERA" for o in bpy.data.objects)

    s.build_armature = s.build_camera = False
    with pytest.raises(RuntimeError, match="Nothing to build"):
        bpy.ops.monoskel.build_all()


def test_build_without_estimate_says_why(empty_scene):
    import bpy

    with pytest.raises(RuntimeError, match="Run Estimate first"):
        bpy.ops.monoskel.build_armature()
    assert not bpy.ops.monoskel.build_all.poll()
    assert len(bpy.data.objects) == 0


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # 0/0 in the core while it finds the lengths unusable
def test_failed_build_leaves_no_objects(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, _, est = _scene_with_estimate(n_frames=8)
    est.proportions = {k: 0.0 for k in est.proportions}  # no positive bone length: the builder must refuse
    scene_data.store_estimate(scene, est)
    before = {"objects": len(bpy.data.objects), "armatures": len(bpy.data.armatures),
              "cameras": len(bpy.data.cameras), "actions": len(bpy.data.actions)}
    with pytest.raises(RuntimeError) as info:
        bpy.ops.monoskel.build_all()
    assert len(str(info.value).strip().splitlines()) == 1
    after = {"objects": len(bpy.data.objects), "armatures": len(bpy.data.armatures),
             "cameras": len(bpy.data.cameras), "actions": len(bpy.data.actions)}
    assert after == before
    assert scene.monoskel.armature is None


def test_build_all_removes_the_armature_when_the_camera_fails(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, _, est = _scene_with_estimate(n_frames=8)
    est.diagnostics["world_from_cam0"] = [[1.0, 0.0], [0.0, 1.0]]  # malformed: only the camera step reads it
    scene_data.store_estimate(scene, est)
    scene.monoskel.build_motion = False
    # The armature step alone succeeds with this estimate, so Build All fails in its second step.
    assert bpy.ops.monoskel.build_armature() == {"FINISHED"}
    first = scene.monoskel.armature
    counts = (len(bpy.data.objects), len(bpy.data.armatures), len(bpy.data.actions), len(bpy.data.cameras))
    with pytest.raises(RuntimeError, match="world_from_cam0"):
        bpy.ops.monoskel.build_all()
    assert (len(bpy.data.objects), len(bpy.data.armatures), len(bpy.data.actions), len(bpy.data.cameras)) == counts
    assert scene.monoskel.camera is None
    assert first.name in bpy.data.objects  # the earlier, separately built armature is untouched
    assert scene.monoskel.armature == first


def test_undo_removes_what_build_all_made(empty_scene):
    """Headless undo works with explicit steps: operators run from Python push none themselves."""
    import bpy

    _scene_with_estimate(n_frames=8)
    bpy.ops.ed.undo_push(message="before build")
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert len(bpy.data.objects) > 0
    bpy.ops.ed.undo_push(message="after build")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert len(bpy.data.objects) == 0
    assert scene.monoskel.armature is None and scene.monoskel.camera is None
    assert scene.monoskel.has_estimate  # the data from before the build is still there
    bpy.ops.ed.redo()
    assert bpy.context.scene.monoskel.armature is not None


def test_scene_changing_operators_declare_undo(blender):
    import bpy

    for name in ("import_tracks", "clip_add_joint_tracks", "clip_to_tracks", "import_test_data", "estimate",
                 "build_armature", "build_camera", "build_all", "refresh"):
        cls = getattr(bpy.types, f"MONOSKEL_OT_{name}")
        assert {"REGISTER", "UNDO"} <= set(cls.bl_options), name


def test_export_bvh_and_fbx_write_files(empty_scene, tmp_path):
    import bpy

    scene, _, est = _scene_with_estimate(n_frames=10)
    with pytest.raises(RuntimeError, match="Build the armature first"):
        bpy.ops.monoskel.export_bvh(filepath=str(tmp_path / "x.bvh"))
    bpy.ops.monoskel.build_all()
    bvh, fbx = tmp_path / "out.bvh", tmp_path / "out.fbx"
    assert bpy.ops.monoskel.export_bvh(filepath=str(bvh)) == {"FINISHED"}
    assert bpy.ops.monoskel.export_fbx(filepath=str(fbx)) == {"FINISHED"}
    text = bvh.read_text()
    assert text.startswith("HIERARCHY") and f"Frames: {len(est.frames)}" in text
    assert fbx.stat().st_size > 1000
    assert scene.monoskel.bvh_path == str(bvh)
    with pytest.raises(RuntimeError, match="does not exist"):
        bpy.ops.monoskel.export_bvh(filepath=str(tmp_path / "missing" / "x.bvh"))


def test_pose_keys_put_bones_on_the_estimated_joints(empty_scene):
    """The armature built from a rigid truth reproduces its 3D joints (world placement from the estimate)."""
    import bpy

    from monoskel.blender.build import world_joints
    from monoskel.blender.build_armature import BONE_FOR_JOINT
    from monoskel.core.skeleton import JOINTS

    scene, _, est = _scene_with_estimate(n_frames=6)
    bpy.ops.monoskel.build_armature()
    arm = scene.monoskel.armature
    idx, joints = world_joints(est, HEIGHT)
    frame = int(idx[-1])
    scene.frame_set(scene.monoskel.tracks_first_frame + frame)
    world = arm.matrix_world
    got = []
    for name in JOINTS:
        bone = arm.pose.bones[BONE_FOR_JOINT[name]] if name in BONE_FOR_JOINT else None
        point = bone.tail if bone is not None else arm.pose.bones["spine_lower"].head
        got.append(world @ point)
    np.testing.assert_allclose(np.array(got), joints[-1], atol=2e-3)


def _datablock_counts():
    import bpy

    return {kind: len(getattr(bpy.data, kind)) for kind in ("objects", "armatures", "cameras", "actions", "meshes",
                                                             "collections")}


def test_building_again_replaces_instead_of_adding_copies(empty_scene):
    """Five Build All rounds (and single-step rebuilds) leave what one leaves, under the same names."""
    import bpy

    scene, _, est = _scene_with_estimate(n_frames=12)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    once = _datablock_counts()
    names = sorted(bpy.data.objects.keys())
    for _ in range(4):
        assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert bpy.ops.monoskel.build_armature() == {"FINISHED"}
    assert bpy.ops.monoskel.build_camera() == {"FINISHED"}
    assert _datablock_counts() == once
    assert sorted(bpy.data.objects.keys()) == names
    s = scene.monoskel
    assert s.armature.name == "MonoSkel" and s.camera.name == "MonoSkel Camera" and scene.camera == s.camera
    assert s.armature.animation_data.action.name == "MonoSkelAction"
    # no orphans: every action and camera in the file is used by the built objects
    assert all(a.users > 0 for a in bpy.data.actions) and all(c.users > 0 for c in bpy.data.cameras)


def test_failed_rebuild_keeps_the_previous_build(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    scene, _, est = _scene_with_estimate(n_frames=8)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    before = (_datablock_counts(), sorted(bpy.data.objects.keys()))
    est.diagnostics["world_from_cam0"] = [[1.0, 0.0], [0.0, 1.0]]   # the camera step fails
    scene_data.store_estimate(scene, est)
    with pytest.raises(RuntimeError, match="world_from_cam0"):
        bpy.ops.monoskel.build_all()
    assert (_datablock_counts(), sorted(bpy.data.objects.keys())) == before
    assert scene.monoskel.armature.name == "MonoSkel" and scene.monoskel.camera.name == "MonoSkel Camera"


def test_problems_become_timeline_markers_and_stale_ones_go(empty_scene):
    """Rejected, swapped and poorly fitting frames mark the timeline; a rebuild of another estimate drops
    the markers that no longer apply."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.review.markers import problem_markers

    scene, _, est = _scene_with_estimate(n_frames=20)
    est.frames[3].rejected = ["l_wrist"]
    est.frames[4].rejected = ["l_wrist"]
    est.frames[10].swapped = ["legs"]
    for i, fr in enumerate(est.frames):
        fr.reprojection_px = 9.0 if i == 15 else 1.0
    est.diagnostics["self_check"] = {"flags": [], "metrics": {}, "worst_frames": [15, 2]}
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    first = scene.monoskel.tracks_first_frame
    marks = {(m.name, m.frame) for m in scene.timeline_markers}
    assert {("input: rejected joints", 3 + first), ("input: left/right undone", 10 + first),
            ("fit: poor", 15 + first)} <= marks
    assert ("input: rejected joints", 4 + first) not in marks          # one marker per run
    assert set(problem_markers(est, first)) <= marks
    # the sidebar lists the worst frames with a button that goes there
    from monoskel.ui import state

    jumps = [r for r in state.section_rows("results", scene.monoskel) if r.op == "monoskel.jump_to_frame"]
    assert [dict(r.op_props)["frame"] for r in jumps] == [15 + first, 2 + first] and jumps[0].enabled
    assert bpy.ops.monoskel.jump_to_frame(frame=15 + first) == {"FINISHED"}
    assert scene.frame_current == 15 + first
    # another estimate without those problems: its rebuild removes their markers
    for fr in est.frames:
        fr.rejected = fr.swapped = None
        fr.reprojection_px = 1.0
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert not [m for m in scene.timeline_markers if m.name.startswith(("input: ", "fit: "))]
