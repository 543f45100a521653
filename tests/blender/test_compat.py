"""The animation shim: one code path for 4.2's flat actions and 4.4+/5.0's slotted actions."""

import bpy
import numpy as np
import pytest


def test_keys_land_where_the_running_blender_keeps_them(empty_scene):
    """4.2-4.3: on the action itself; 4.4+: in the channelbag of the ID's slot (5.0 has no action.fcurves)."""
    from monoskel.blender import compat

    obj = bpy.data.objects.new("probe", None)
    empty_scene.collection.objects.link(obj)
    fcurves = compat.ensure_fcurves(obj)
    compat.set_keys(fcurves, "location", 0, [1, 2], [0.0, 1.0])
    action = obj.animation_data.action
    if bpy.app.version >= (4, 4, 0):
        slot = obj.animation_data.action_slot
        assert slot is not None and slot.target_id_type == 'OBJECT'
        bag = action.layers[0].strips[0].channelbag(slot)
        assert [fc.data_path for fc in bag.fcurves] == ["location"]
    else:
        assert [fc.data_path for fc in action.fcurves] == ["location"]
    if bpy.app.version >= (5, 0, 0):
        assert not hasattr(action, "fcurves")


def test_bulk_keys_read_back_and_evaluate(empty_scene):
    from monoskel.blender import compat

    obj = bpy.data.objects.new("probe", None)
    empty_scene.collection.objects.link(obj)
    frames = np.arange(1, 501)
    values = np.sin(frames / 30.0)
    fcurves = compat.ensure_fcurves(obj)
    fc = compat.set_keys(fcurves, "location", 2, frames, values, group="Probe")
    assert fc.group is not None and fc.group.name == "Probe"
    got_frames, got_values = compat.get_keys(obj, "location", 2)
    assert np.array_equal(got_frames, frames)
    assert np.allclose(got_values, values, atol=1e-6)
    assert {kp.interpolation for kp in fc.keyframe_points} == {'LINEAR'}
    empty_scene.frame_set(250)
    assert obj.location.z == pytest.approx(values[249], abs=1e-6)
    assert compat.fcurve_paths(obj) == {("location", 2)}


def test_rewriting_replaces_keys_and_interpolation(empty_scene):
    from monoskel.blender import compat

    obj = bpy.data.objects.new("probe", None)
    empty_scene.collection.objects.link(obj)
    fcurves = compat.ensure_fcurves(obj)
    compat.set_keys(fcurves, '["flag"]', 0, [1, 2, 3], [0, 1, 0])
    fc = compat.set_keys(compat.ensure_fcurves(obj), '["flag"]', 0, [1, 5], [1, 0], interpolation='CONSTANT')
    assert len(fc.keyframe_points) == 2
    assert {kp.interpolation for kp in fc.keyframe_points} == {'CONSTANT'}
    assert len(bpy.data.actions) == 1  # the same action was reused


def test_object_data_gets_its_own_action_and_slot(empty_scene):
    from monoskel.blender import compat

    cam_data = bpy.data.cameras.new("lens probe")
    obj = bpy.data.objects.new("cam probe", cam_data)
    empty_scene.collection.objects.link(obj)
    compat.set_keys(compat.ensure_fcurves(cam_data), "lens", 0, [1, 11], [20.0, 70.0])
    compat.set_keys(compat.ensure_fcurves(obj), "rotation_euler", 2, [1, 11], [0.0, 1.0])
    assert cam_data.animation_data.action != obj.animation_data.action
    if compat.SLOTTED_ACTIONS:
        assert cam_data.animation_data.action_slot.target_id_type == 'CAMERA'
    empty_scene.frame_set(6)
    assert cam_data.lens == pytest.approx(45.0)
    assert compat.get_keys(obj, "lens") is None


def test_mismatched_keys_are_refused(empty_scene):
    from monoskel.blender import compat

    obj = bpy.data.objects.new("probe", None)
    with pytest.raises(ValueError, match="location"):
        compat.set_keys(compat.ensure_fcurves(obj), "location", 0, [1, 2, 3], [0.0, 1.0])
