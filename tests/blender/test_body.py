"""D'Apuzzo's metaball body on the built armature: one ellipsoid per bone, as thick as an
adult's limb, moving with the motion; built again it replaces itself; undo takes it away."""

from __future__ import annotations

import numpy as np
import pytest

from tests.blender.rigs import walk_take


def _surface(obj):
    import bpy

    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    mesh = ev.to_mesh()
    try:
        return np.array([(ev.matrix_world @ v.co)[:] for v in mesh.vertices])
    finally:
        ev.to_mesh_clear()


def _thigh_radius(points, arm):
    pb = arm.pose.bones["thigh.L"]
    head, tail = np.array(arm.matrix_world @ pb.head), np.array(arm.matrix_world @ pb.tail)
    axis = (tail - head) / np.linalg.norm(tail - head)
    rel = points - 0.5 * (head + tail)
    along = rel @ axis
    perp = np.linalg.norm(rel - np.outer(along, axis), axis=1)
    return float(np.median(perp[(np.abs(along) < 0.03) & (perp < 0.12)]))


def test_body_is_built_on_the_bones_moves_with_them_and_replaces_itself(empty_scene):
    import bpy

    scene = walk_take()
    arm = scene.monoskel.armature
    assert bpy.ops.monoskel.build_body() == {"FINISHED"}
    metas = [o for o in arm.children if o.get("monoskel_body")]
    assert len(metas) == 16 and all(o.parent_type == 'BONE' for o in metas)
    assert {o.users_collection[0] for o in metas} == {arm.users_collection[0]}          # in the take
    base = next(o for o in metas if "." not in o.name)
    first = scene.frame_start
    scene.frame_set(first)
    pts = _surface(base)
    assert _thigh_radius(pts, arm) == pytest.approx(0.085 * scene.monoskel.height_m / 1.75, rel=0.15)
    heights = pts[:, 2]
    assert heights.max() == pytest.approx(scene.monoskel.height_m, abs=0.08) and heights.min() < 0.15
    pelvis0 = np.array(arm.matrix_world @ arm.pose.bones["spine_lower"].head)
    centre0 = pts.mean(axis=0)
    scene.frame_set(first + 60)
    pelvis1 = np.array(arm.matrix_world @ arm.pose.bones["spine_lower"].head)
    moved = _surface(base).mean(axis=0) - centre0
    assert np.linalg.norm(pelvis1 - pelvis0) > 0.3
    assert np.linalg.norm(moved[:2] - (pelvis1 - pelvis0)[:2]) < 0.1                     # the body went along
    # again: the old body goes, one body stays
    assert bpy.ops.monoskel.build_body() == {"FINISHED"}
    assert len([o for o in arm.children if o.get("monoskel_body")]) == 16
    assert sum(o.type == 'META' for o in bpy.data.objects) == 16


def test_build_body_needs_an_armature(empty_scene):
    import bpy

    with pytest.raises(RuntimeError):
        bpy.ops.monoskel.build_body()
