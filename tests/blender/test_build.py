"""The builders put the estimate into the scene exactly: lengths, pose, camera, tracks, diagnostics.

Expected values are computed here from the estimate with independent formulas
(not through the builder's own helpers), and the scene is read back the way
Blender shows it: evaluated depsgraph poses, world matrices, F-curve keys.
"""

import math

import bpy
import numpy as np
import pytest
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

FLIP_YZ = np.diag([1.0, -1.0, -1.0])  # our camera axes <-> Blender camera local axes


def _rot(axis, deg):
    a = np.radians(deg)
    c, s = math.cos(a), math.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m


def rigid_estimate(n_frames=6, seed=0, *, height_m=1.8, world=None, camera=True):
    """A rigid figure with random segment directions, 5 m in front of the camera (frame-0 camera axes)."""
    from monoskel.core.result import Estimate, FrameEstimate
    from monoskel.core.skeleton import SEGMENT_CLASS, SEGMENTS, class_lengths_for_height, proportions_dict

    rng = np.random.default_rng(seed)
    props = rng.uniform(0.5, 1.5, 10) * np.array([0.06, 0.2, 0.2, 0.1, 0.1, 0.05, 0.09, 0.07, 0.16, 0.14])
    props /= props.sum()
    lengths = class_lengths_for_height(props, height_m)
    joints = np.zeros((n_frames, 17, 3))
    joints[:, 0] = np.array([0.2, 0.3, 5.0]) + rng.normal(scale=0.2, size=(n_frames, 3))
    for s, (p, c) in enumerate(SEGMENTS):
        d = rng.normal(size=(n_frames, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        joints[:, c] = joints[:, p] + lengths[SEGMENT_CLASS[s]] * d
    frames = []
    for i in range(n_frames):
        moving = camera and i >= n_frames // 2
        rot = (3.0 * (i - n_frames // 2), -1.5 * (i - n_frames // 2), 0.5) if moving else (0.0, 0.0, 0.0)
        frames.append(FrameEstimate(stance=("l", "r", None)[i % 3], camera_moving=moving, rotvec_deg=rot,
                                    focal_mm=35.0 + (2.0 * i if moving else 0.0), scale=1.0 + 0.02 * i,
                                    joints_3d=joints[i].tolist(), reprojection_px=(0.25 * i if i % 2 else None)))
    diag = {} if world is None else {"world_from_cam0": world.tolist()}
    est = Estimate("test", proportions_dict(props), 35.0, frames, height_m=height_m, diagnostics=diag)
    return est, joints, props


def synthetic_estimate(n_frames=40, seed=0, noise_px=0.0):
    """Generator output (moving camera, truth as the estimate) for end-to-end camera checks."""
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    motion = load_motion("builtin:walk", max_frames=n_frames, fps=10)
    tracks, truth = synthesize(motion, kinds=("pan", "tilt", "zoom"), noise_px=noise_px, seed=seed,
                               continuous=True)
    return tracks, truth, truth_as_estimate(truth)


def _posed(obj, frame):
    scene = bpy.context.scene
    scene.frame_set(frame)
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mw = np.array(ev.matrix_world)
    heads = {pb.name: mw[:3, :3] @ np.array(pb.head) + mw[:3, 3] for pb in ev.pose.bones}
    tails = {pb.name: mw[:3, :3] @ np.array(pb.tail) + mw[:3, 3] for pb in ev.pose.bones}
    return heads, tails


def _datablock_counts():
    kinds = ("objects", "armatures", "cameras", "actions", "collections", "meshes")
    return {k: len(getattr(bpy.data, k)) for k in kinds}


def test_bone_lengths_equal_proportions_times_height_and_rest_is_a_t_pose(empty_scene):
    from monoskel.blender import build
    from monoskel.core.skeleton import ANKLE_HEIGHT_FRACTION, SEGMENT_CLASS, class_lengths_for_height

    est, _, props = rigid_estimate()
    obj = build.build_armature(empty_scene, est, height_m=1.62, with_motion=False)
    bones = obj.data.bones
    assert len(bones) == 16 == len(build.BONES)
    expected = class_lengths_for_height(props, 1.62)
    for s, (name, _, _, parent) in enumerate(build.BONES):
        assert bones[name].length == pytest.approx(expected[SEGMENT_CLASS[s]], abs=1e-5)
        assert (bones[name].parent.name if bones[name].parent else None) == parent
    # T-pose, Z up, facing -Y: legs down to ankle height, arms level and sideways, spine up.
    ankle_z = ANKLE_HEIGHT_FRACTION * 1.62
    for side, sign in (("L", 1), ("R", -1)):
        assert bones[f"shin.{side}"].tail_local.z == pytest.approx(ankle_z, abs=1e-5)
        for arm in ("clavicle", "upper_arm", "forearm"):
            v = bones[f"{arm}.{side}"].tail_local - bones[f"{arm}.{side}"].head_local
            assert v.normalized().x == pytest.approx(sign, abs=1e-6)
    # Head top + ankle height == stature.
    assert bones["head"].tail_local.z == pytest.approx(1.62, abs=1e-4)
    assert bones["spine_lower"].parent is None
    assert obj.animation_data is None or obj.animation_data.action is not None  # diagnostics only


@pytest.mark.parametrize("given_world", [True, False])
def test_pose_keys_reproduce_the_3d_joints(empty_scene, given_world):
    from monoskel.blender import build
    from monoskel.core.skeleton import ANKLE_HEIGHT_FRACTION, JOINT_INDEX

    world = None
    if given_world:
        world = np.eye(4)
        world[:3, :3] = _rot(2, 30) @ _rot(0, -95)
        world[:3, 3] = (1.0, -2.0, 1.4)
    est, joints, _ = rigid_estimate(n_frames=6, seed=3, world=world)
    obj = build.build_armature(empty_scene, est, height_m=1.8)
    if given_world:
        expected = joints @ world[:3, :3].T + world[:3, 3]
    else:  # documented default: world = (x, z_cam, -y_cam), lifted so the lowest ankle is at ankle height
        expected = np.stack([joints[..., 0], joints[..., 2], -joints[..., 1]], axis=-1)
        feet = expected[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 2]
        expected[..., 2] += ANKLE_HEIGHT_FRACTION * 1.8 - feet.min()
    for f in (0, 2, 5):
        heads, tails = _posed(obj, f + 1)
        assert np.linalg.norm(heads["spine_lower"] - expected[f, 0]) < 1e-3
        for name, head, tail, _ in build.BONES:
            assert np.linalg.norm(heads[name] - expected[f, JOINT_INDEX[head]]) < 1e-3, (f, name)
            assert np.linalg.norm(tails[name] - expected[f, JOINT_INDEX[tail]]) < 1e-3, (f, name)


def test_building_taller_scales_the_whole_scene(empty_scene):
    from monoskel.blender import build
    from monoskel.core.skeleton import JOINT_INDEX

    world = np.eye(4)
    world[:3, :3] = _rot(0, -90)
    world[:3, 3] = (0.0, 0.0, 1.5)
    est, joints, _ = rigid_estimate(n_frames=3, seed=5, world=world, height_m=1.5)
    out = build.build_all(empty_scene, est, height_m=3.0)
    heads, _ = _posed(out["armature"], 2)
    expected = 2.0 * (joints[1] @ world[:3, :3].T + world[:3, 3])
    assert np.linalg.norm(heads["thigh.L"] - expected[JOINT_INDEX["l_hip"]]) < 1e-3
    assert np.allclose(out["camera"].matrix_world.translation, 2.0 * world[:3, 3], atol=1e-6)


@pytest.mark.parametrize("image_size, sensor", [((720, 480), 36.0), ((640, 480), 32.0), ((1920, 1080), 36.0)])
def test_camera_keys_equal_the_estimate_per_frame(empty_scene, image_size, sensor):
    from monoskel.blender import build, compat
    from monoskel.core.camera import rotation_matrix
    from monoskel.core.tracks import Tracks

    world = np.eye(4)
    world[:3, :3] = _rot(2, -20) @ _rot(0, -100)
    world[:3, 3] = (0.5, -4.0, 1.3)
    est, _, _ = rigid_estimate(n_frames=10, seed=1, world=world)
    tracks = Tracks(np.full((10, 17, 2), 100.0), np.ones((10, 17)), 25.0, image_size)
    cam = build.build_camera(empty_scene, est, tracks, height_m=est.height_m)
    assert cam.data.sensor_fit == 'HORIZONTAL'
    assert cam.data.sensor_width == pytest.approx(sensor)
    r = empty_scene.render
    assert (r.resolution_x, r.resolution_y, r.fps) == (image_size[0], image_size[1], 25)
    assert (empty_scene.frame_start, empty_scene.frame_end) == (1, 10)
    assert empty_scene.camera == cam
    assert np.allclose(cam.matrix_world.translation, world[:3, 3], atol=1e-6)
    for i, fr in enumerate(est.frames):
        empty_scene.frame_set(i + 1)
        m = np.array(cam.matrix_world)[:3, :3]
        r_i = (world[:3, :3].T @ m @ FLIP_YZ).T  # X_i = R_i X_0
        assert np.allclose(r_i, rotation_matrix(np.array(fr.rotvec_deg)), atol=1e-5), i
        assert cam.data.lens == pytest.approx(fr.focal_mm, abs=1e-4)
    # Still frames are held by two keys; moving frames are keyed one by one.
    frames, _ = compat.get_keys(cam, "rotation_euler", 0)
    moving = [i + 1 for i, fr in enumerate(est.frames) if fr.camera_moving]
    assert set(moving) <= set(frames.astype(int))
    assert len(frames) < len(est.frames)


def test_a_still_spell_that_wobbles_below_the_hold_tolerance_is_two_keys(empty_scene):
    """A solved still camera wobbles by ~0.001 deg; it must still read as a hold, within the tolerance."""
    import dataclasses

    from monoskel.blender import build, build_camera, compat

    est, _, _ = rigid_estimate(n_frames=12, seed=2)
    rng = np.random.default_rng(0)
    frames = []
    for i, fr in enumerate(est.frames):
        moving = 6 <= i < 9
        rot = (0.0, 0.3 * (i - 5), 0.0) if moving else ((0.0, 0.0, 0.0) if i < 6 else (0.0, 1.2, 0.0))
        wobble = rng.uniform(-1, 1, 3) * 0.0008  # degrees, well inside the 0.002 deg hold
        frames.append(dataclasses.replace(fr, camera_moving=moving, rotvec_deg=tuple(np.add(rot, wobble)),
                                          focal_mm=50.0 + rng.uniform(-1, 1) * 0.0004))
    est = dataclasses.replace(est, frames=frames)
    cam = build.build_camera(empty_scene, est, None, height_m=est.height_m)
    keyed, _ = compat.get_keys(cam, "rotation_euler", 1)
    keyed = set(keyed.astype(int))
    assert {7, 8, 9} <= keyed                       # the moving frames (1-based)
    assert len(keyed & set(range(2, 6))) == 0       # inside the first still spell: no keys
    for i, fr in enumerate(est.frames):             # and the curve stays within the tolerance
        empty_scene.frame_set(i + 1)
        assert cam.data.lens == pytest.approx(fr.focal_mm, abs=build_camera.LENS_HOLD_MM)


def test_camera_spells_become_timeline_markers_once(empty_scene):
    from monoskel.blender import build

    est, _, _ = rigid_estimate(n_frames=8, seed=1)
    est.diagnostics["spells"] = [{"start": 0, "end": 3, "kind": "still"}, {"start": 4, "end": 7, "kind": "pan"}]
    build.build_camera(empty_scene, est)
    build.build_camera(empty_scene, est)
    assert sorted((m.frame, m.name) for m in empty_scene.timeline_markers) == [(1, "camera: still"),
                                                                             (5, "camera: pan")]


def test_camera_sees_the_armature_on_the_tracks(empty_scene):
    """End to end: generator truth built into Blender projects back onto the 2D tracks (no noise)."""
    from monoskel.blender import build
    from monoskel.core.skeleton import JOINT_INDEX, JOINTS

    tracks, truth, est = synthetic_estimate(n_frames=40, seed=0)
    assert est.frames[-1].camera_moving or any(fr.camera_moving for fr in est.frames)
    tracks.xy[17, 5], tracks.conf[17, 5] = np.nan, 0.0  # one missing observation, hidden on its frame
    out = build.build_all(empty_scene, est, tracks, height_m=float(truth.height_m))
    arm, cam, view = out["armature"], out["camera"], out["tracks"]
    markers = {o.name.rsplit(".", 1)[1]: o for o in view.children if o.type == 'EMPTY'}
    (lines,) = [o for o in view.children if o.type == 'MESH']
    assert sorted(markers) == sorted(JOINTS) and len(lines.data.edges) == 16
    w, h = tracks.image_size
    worst = 0.0
    for f in (0, 17, 25, 39):
        heads, tails = _posed(arm, f + 1)
        points = {"pelvis": heads["spine_lower"]}
        points.update({tail: tails[name] for name, _, tail, _ in build.BONES})
        ev = lines.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mw = np.array(ev.matrix_world)
        drawn = [mw[:3, :3] @ np.array(v.co) + mw[:3, 3] for v in ev.to_mesh().vertices]
        for j, joint in enumerate(JOINTS):  # the line mesh follows the markers
            assert np.allclose(drawn[j], markers[joint].matrix_world.translation, atol=1e-5)
        ev.to_mesh_clear()
        for joint in JOINTS:
            # the detector's confidence is keyed on the marker (0 where missing): the Graph Editor plots it
            assert markers[joint]["monoskel_confidence"] == pytest.approx(tracks.conf[f, JOINT_INDEX[joint]])
            if not tracks.present[f, JOINT_INDEX[joint]]:
                assert markers[joint].hide_viewport
                continue
            assert not markers[joint].hide_viewport
            for p in (points[joint], np.array(markers[joint].matrix_world.translation)):
                ndc = world_to_camera_view(empty_scene, cam, Vector(p))
                px = np.array([ndc.x * w, (1.0 - ndc.y) * h])
                worst = max(worst, float(np.linalg.norm(px - tracks.xy[f, JOINT_INDEX[joint]])))
    assert worst < 0.05


def test_diagnostics_are_keyed_custom_properties(empty_scene):
    from monoskel.blender import build, compat

    est, _, _ = rigid_estimate(n_frames=7, seed=2)
    obj = build.build_armature(empty_scene, est, with_motion=False)
    frames, scale = compat.get_keys(obj, '["monoskel_virtual_scale"]')
    assert np.allclose(frames, np.arange(1, 8)) and np.allclose(scale, [fr.scale for fr in est.frames], atol=1e-6)
    _, stance = compat.get_keys(obj, '["monoskel_stance"]')
    assert stance.tolist() == [{"l": 1, "r": 2, None: 0}[fr.stance] for fr in est.frames]
    frames, err = compat.get_keys(obj, '["monoskel_reprojection_px"]')
    have = [(i + 1, fr.reprojection_px) for i, fr in enumerate(est.frames) if fr.reprojection_px is not None]
    assert frames.tolist() == [f for f, _ in have] and np.allclose(err, [v for _, v in have])
    for frame, code in ((3, 0.0), (5, 2.0)):  # stance of index 2 is None, of index 4 is "r"
        empty_scene.frame_set(frame)
        assert obj.evaluated_get(bpy.context.evaluated_depsgraph_get())["monoskel_stance"] == code


def test_a_failure_midway_removes_everything_the_build_made(empty_scene):
    from monoskel.blender import build
    from monoskel.core.result import FrameEstimate
    from monoskel.core.tracks import Tracks

    est, _, _ = rigid_estimate(n_frames=5, seed=4)
    before = _datablock_counts()
    range_before = (empty_scene.frame_start, empty_scene.frame_end, empty_scene.render.fps)

    def cancel_after_armature(level, message):
        if message.startswith("armature"):
            raise KeyboardInterrupt("user cancelled")

    def cancel_after_camera(level, message):
        if message.startswith("camera"):
            raise KeyboardInterrupt("user cancelled")

    est.diagnostics["spells"] = [{"start": 0, "end": 2, "kind": "still"}, {"start": 3, "end": 4, "kind": "pan"}]
    tracks = Tracks(np.full((5, 17, 2), 60.0), np.ones((5, 17)), 24.0, (720, 480))
    for cancel in (cancel_after_armature, cancel_after_camera):
        with pytest.raises(KeyboardInterrupt):
            build.build_all(empty_scene, est, tracks, height_m=1.7, report=cancel)
        assert _datablock_counts() == before
        assert len(empty_scene.timeline_markers) == 0
    assert (empty_scene.frame_start, empty_scene.frame_end, empty_scene.render.fps) == range_before

    from monoskel.core.errors import InputError

    with pytest.raises(InputError, match="5 frames but the tracks have 4"):  # found after the armature exists
        build.build_all(empty_scene, est, Tracks(tracks.xy[:4], tracks.conf[:4], 24.0, (720, 480)))
    assert _datablock_counts() == before

    est.frames[3] = FrameEstimate(joints_3d=[[0.0, 0.0, 1.0]] * 16)  # malformed: found after bones exist
    with pytest.raises(ValueError, match="frame 3"):
        build.build_armature(empty_scene, est)
    assert _datablock_counts() == before
    assert bpy.context.mode == 'OBJECT'


def test_building_twice_gives_two_independent_rigs(empty_scene):
    from monoskel.blender import build

    est, _, _ = rigid_estimate(n_frames=4, seed=6)
    first = build.build_all(empty_scene, est, height_m=1.8)
    second = build.build_all(empty_scene, est, height_m=1.8)
    assert first["armature"] != second["armature"] and first["camera"] != second["camera"]
    assert first["armature"].animation_data.action != second["armature"].animation_data.action


def test_remove_built_takes_everything_a_build_made(empty_scene):
    from monoskel.blender import build
    from monoskel.core.tracks import Tracks

    est, _, _ = rigid_estimate(n_frames=4, seed=7)
    before = _datablock_counts()
    tracks = Tracks(np.full((4, 17, 2), 50.0), np.ones((4, 17)), 24.0, (720, 480))
    out = build.build_all(empty_scene, est, tracks, height_m=1.8)
    build.remove_built(out["armature"])
    build.remove_built(out["camera"])
    assert _datablock_counts() == before
