"""Takes: rebuilding replaces the active take, New Take adds one, Delete leaves nothing behind,
undo restores, save and reload keep takes, markers and curves; Compare shows bone and joint differences."""

from __future__ import annotations

import numpy as np
import pytest

KINDS = ("objects", "armatures", "cameras", "actions", "meshes", "collections", "texts", "curves", "materials")


def _counts():
    import bpy

    return {kind: len(getattr(bpy.data, kind)) for kind in KINDS}


def _no_orphans():
    import bpy

    for kind in ("armatures", "cameras", "actions", "meshes", "collections", "curves"):
        orphans = [b.name for b in getattr(bpy.data, kind) if b.users == 0]
        assert not orphans, (kind, orphans)


def _import_walk(tmp_path, n_frames=30):
    import bpy

    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan",), seed=3)
    path = tmp_path / "walk.json"
    write_tracks_json(tracks, path)
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    return tracks


def _scene_with_estimate(n_frames=16):
    """Tracks + the truth of a synthetic walk shaped as an estimate, on the scene."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.test_data import truth_as_estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan", "zoom"), seed=2)
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    est = truth_as_estimate(truth)
    est.method = "test"
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    return scene, tracks, est


def _store(scene, est):
    import bpy

    from monoskel.blender import scene_data

    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}


def test_five_estimate_and_build_rounds_leave_what_one_leaves(empty_scene, tmp_path):
    import bpy

    _import_walk(tmp_path)
    s = empty_scene.monoskel
    s.estimate_focal = False
    s.method = "paper"
    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    once, names = _counts(), sorted(bpy.data.objects.keys())
    assert len(s.takes) == 1 and s.take_active == 0
    assert s.takes[0].collection.name == s.takes[0].name and "walk.json · paper ·" in s.takes[0].name
    assert set(s.takes[0].collection.objects) == set(bpy.data.objects)     # every built object is the take's
    for k in range(4):
        s.method = ("joint", "paper")[k % 2]     # ends on "paper": the label follows each build
        assert bpy.ops.monoskel.estimate() == {"FINISHED"}
        assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert _counts() == once and sorted(bpy.data.objects.keys()) == names
    assert len(s.takes) == 1 and f"· {s.method} ·" in s.takes[0].name
    assert s.armature == s.takes[0].armature and s.armature.name == "MonoSkel"
    assert s.camera == s.takes[0].camera and empty_scene.camera == s.camera
    _no_orphans()


def test_new_take_adds_exactly_one_and_keeps_the_old_one(empty_scene):
    import bpy

    scene, _, _ = _scene_with_estimate()
    empty = _counts()
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    one = _counts()
    first = scene.monoskel.takes[0]
    first_objects = set(first.collection.objects)
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    s = scene.monoskel
    assert len(s.takes) == 2 and s.take_active == 1 and s.take_index == 1
    two = _counts()
    # exactly one more take: every kind grows by what one take holds (the scene's own texts once)
    assert {k: two[k] - one[k] for k in KINDS} == {k: one[k] - empty[k] for k in KINDS}
    assert set(s.takes[0].collection.objects) == first_objects and s.takes[0].armature.name == "MonoSkel"
    assert s.takes[1].armature.name == "MonoSkel 2" and s.takes[1].camera.name == "MonoSkel 2 Camera"
    assert s.armature == s.takes[1].armature and scene.camera == s.takes[1].camera
    # rebuilding now replaces take 2, not take 1
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert _counts() == two and set(s.takes[0].collection.objects) == first_objects
    _no_orphans()


def test_delete_removes_every_data_block_of_the_take(empty_scene):
    import bpy

    scene, _, _ = _scene_with_estimate()
    s = scene.monoskel
    empty = _counts()
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    one = _counts()
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    mine = bpy.data.objects.new("animator's empty", None)            # not the take's: must survive
    s.takes[1].collection.objects.link(mine)
    s.take_index = 1
    assert bpy.ops.monoskel.take_delete() == {"FINISHED"}
    assert len(s.takes) == 1 and s.take_active == 0
    assert _counts() == {**one, "objects": one["objects"] + 1}
    assert mine.name in scene.collection.objects
    assert s.armature == s.takes[0].armature and scene.camera == s.takes[0].camera
    bpy.data.objects.remove(mine)
    s.take_index = 0
    assert bpy.ops.monoskel.take_delete() == {"FINISHED"}
    assert len(s.takes) == 0 and s.armature is None and s.camera is None
    assert _counts() == empty
    assert not [m for m in scene.timeline_markers if m.name.startswith(("camera: ", "input: ", "fit: "))]
    with pytest.raises(RuntimeError, match="Build a take first"):
        bpy.ops.monoskel.take_delete()


def test_a_failed_new_take_leaves_nothing(empty_scene):
    import bpy

    scene, _, est = _scene_with_estimate()
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    before = (_counts(), sorted(bpy.data.objects.keys()))
    est.diagnostics["world_from_cam0"] = [[1.0, 0.0], [0.0, 1.0]]   # the camera step fails
    _store(scene, est)
    with pytest.raises(RuntimeError, match="world_from_cam0"):
        bpy.ops.monoskel.new_take()
    assert (_counts(), sorted(bpy.data.objects.keys())) == before
    assert len(scene.monoskel.takes) == 1 and scene.monoskel.take_active == 0


def test_one_undo_step_restores_the_previous_take(empty_scene):
    import bpy

    from monoskel.blender.build_armature import BONES

    scene, _, est = _scene_with_estimate()
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    lengths = {b.name: b.length for b in scene.monoskel.armature.data.bones}
    bpy.ops.ed.undo_push(message="take 1 built")
    est.proportions = {k: v * (1.2 if k == "thigh" else 1.0) for k, v in est.proportions.items()}
    _store(scene, est)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="rebuilt and a new take")
    bpy.ops.ed.undo()
    s = bpy.context.scene.monoskel
    assert len(s.takes) == 1 and s.armature.name == "MonoSkel"
    assert {b.name: b.length for b in s.armature.data.bones} == pytest.approx(lengths)
    assert len(lengths) == len(BONES)


def test_save_and_reload_keep_takes_markers_and_curves(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import compat

    scene, _, est = _scene_with_estimate(n_frames=20)
    est.frames[4].rejected = ["l_wrist"]
    for i, fr in enumerate(est.frames):
        fr.reprojection_px = 1.0 + 0.01 * i
    _store(scene, est)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    first = scene.monoskel.tracks_first_frame
    marks = {(m.name, m.frame) for m in scene.timeline_markers}
    assert ("input: rejected joints", 4 + first) in marks
    names = [t.name for t in scene.monoskel.takes]
    path = tmp_path / "takes.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path))
    scene = bpy.context.scene
    s = scene.monoskel
    assert [t.name for t in s.takes] == names and s.take_active == 1
    for take in s.takes:
        assert take.armature is not None and take.camera is not None and take.estimate is not None
        assert take.armature.name in take.collection.objects
    assert {(m.name, m.frame) for m in scene.timeline_markers} == marks
    frames, values = compat.get_keys(s.armature, '["monoskel_reprojection_px"]')
    assert len(frames) == 20 and values[5] == pytest.approx(1.05, abs=1e-4)
    view = bpy.data.objects[f"{s.camera.name} Tracks.l_wrist"]
    frames, values = compat.get_keys(view, '["monoskel_confidence"]')
    assert len(frames) == 20 and max(values) > 0
    _no_orphans()


def test_make_active_switches_camera_and_markers(empty_scene):
    import bpy

    scene, _, est = _scene_with_estimate(n_frames=20)
    first = scene.monoskel.tracks_first_frame
    est.frames[6].swapped = ["legs"]
    _store(scene, est)
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    est.frames[6].swapped = None
    _store(scene, est)
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    s = scene.monoskel
    swapped = ("input: left/right undone", 6 + first)
    assert swapped not in {(m.name, m.frame) for m in scene.timeline_markers}
    s.take_index = 0
    assert bpy.ops.monoskel.take_make_active() == {"FINISHED"}
    assert s.take_active == 0 and scene.camera == s.takes[0].camera and s.armature == s.takes[0].armature
    assert swapped in {(m.name, m.frame) for m in scene.timeline_markers}
    # Build now replaces take 1, the active one
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    assert s.takes[0].armature.name == "MonoSkel" and s.takes[1].armature.name == "MonoSkel 2"


def test_compare_shows_bone_and_joint_differences(empty_scene):
    import bpy

    from monoskel.blender import compat
    from monoskel.blender.review.takes import DIFF_PROPERTY
    from monoskel.core.skeleton import CLASSES, class_lengths_for_height
    from monoskel.ui import state

    scene, _, est = _scene_with_estimate(n_frames=16)
    s = scene.monoskel
    s.height_m = float(est.height_m)          # one world scale: a shift in the estimate is a shift in the scene
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    lengths_a = class_lengths_for_height(est.proportions_vector(), s.height_m)
    shift = np.array([0.0, 0.0, 0.04])         # 4 cm along the camera axis at frame 9 only
    est.frames[9].joints_3d = (np.array(est.frames[9].joints_3d) + shift).tolist()
    est.proportions = {k: v * (1.1 if k == "forearm" else 1.0) for k, v in est.proportions.items()}
    _store(scene, est)
    assert bpy.ops.monoskel.new_take() == {"FINISHED"}
    lengths_b = class_lengths_for_height(est.proportions_vector(), s.height_m)
    with pytest.raises(RuntimeError, match="other than the active"):
        bpy.ops.monoskel.take_compare()           # the selection is the active take
    s.take_index = 0
    assert bpy.ops.monoskel.take_compare() == {"FINISHED"}
    rows = state.section_rows("takes", s)
    texts = [r.text for r in rows]
    # take 0 compared against the active take 1: B - A is take 0 - take 1
    table = next(r for r in rows if r.kind == "table").cells
    forearm = next(c for c in table if c[0] == "forearm")
    k = CLASSES.index("forearm")
    assert float(forearm[3]) == pytest.approx(100 * (lengths_a[k] - lengths_b[k]), abs=0.06)
    jumps = [r for r in rows if r.op == "monoskel.jump_to_frame"]
    assert dict(jumps[0].op_props)["frame"] == 9 + s.tracks_first_frame
    assert any(f"{40:.0f} mm max" in t for t in texts), texts
    frames, values = compat.get_keys(s.takes[0].armature, f'["{DIFF_PROPERTY}"]')
    assert len(frames) == 16 and values[9] == pytest.approx(40.0, abs=0.5) and max(np.delete(values, 9)) < 0.5
