"""Our BVH forward kinematics against Blender's own importer (io_anim_bvh).

For every shared clip (first 60 frames), the world position of every joint
from ``core.io.bvh`` must equal the head of the imported armature's pose bone
on every frame, and End Sites the tails of their bones, to 1e-4 of the
figure's height.  The import uses the identity axis conversion
(forward Y, up Z), scale 1 and native rotation modes, so no transform
separates the two.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import bpy
import numpy as np
import pytest

N_FRAMES = 60
_SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "bvh"
CLIPS = sorted(p.name for p in _SHARED.glob("*.bvh")) if _SHARED.is_dir() else []


def _first_frames(source: Path, target: Path, n: int) -> int:
    """Copy ``source`` keeping the hierarchy and its first ``n`` frame lines (text edit, not our writer)."""
    lines = source.read_text().splitlines()
    out, i = [], 0
    while not lines[i].strip().lower().startswith("frames:"):
        out.append(lines[i])
        i += 1
    total = int(lines[i].split(":")[1])
    keep = min(n, total)
    out.append(f"Frames: {keep}")
    i += 1
    while not lines[i].strip():
        i += 1
    out.append(lines[i])   # Frame Time
    frames = [line for line in lines[i + 1:] if line.strip()][:keep]
    target.write_text("\n".join(out + frames) + "\n")
    return keep


def _ensure_bvh_importer():
    if not hasattr(bpy.ops.import_anim, "bvh") or "io_anim_bvh" not in bpy.context.preferences.addons:
        import addon_utils

        addon_utils.enable("io_anim_bvh", default_set=True)
    assert "io_anim_bvh" in bpy.context.preferences.addons


def test_shared_clips_are_present(shared_bvh_dir):
    assert len(list(shared_bvh_dir.glob("*.bvh"))) >= 10


@pytest.mark.parametrize("clip", CLIPS)
def test_forward_kinematics_matches_blender_importer(clip, shared_bvh_dir, empty_scene, blender, tmp_path):
    bvh_module = importlib.import_module(blender.__name__ + ".core.io.bvh")
    path = tmp_path / clip
    n = _first_frames(shared_bvh_dir / clip, path, N_FRAMES)
    ours = bvh_module.read_bvh(path)
    assert ours.n_frames == n
    positions = ours.world_positions()

    _ensure_bvh_importer()
    result = bpy.ops.import_anim.bvh(
        filepath=str(path), target="ARMATURE", global_scale=1.0, frame_start=1, use_fps_scale=False,
        update_scene_fps=False, update_scene_duration=False, use_cyclic=False, rotate_mode="NATIVE",
        axis_forward="Y", axis_up="Z",
    )
    assert result == {"FINISHED"}
    armature = bpy.context.view_layer.objects.active
    assert armature is not None and armature.type == "ARMATURE"
    world = np.array(armature.matrix_world)
    np.testing.assert_allclose(world, np.eye(4), atol=1e-12)     # identity axis conversion

    joint_ids = [j for j in range(ours.n_joints) if not ours.is_end_site[j]]
    bone_names = [ours.names[j] for j in joint_ids]
    assert set(bone_names) <= set(armature.pose.bones.keys())
    # End Sites that define a real bone tail (Blender lengthens zero-length leaf bones)
    tails = [(j, int(ours.parents[j])) for j in range(ours.n_joints)
             if ours.is_end_site[j] and len(ours.children[ours.parents[j]]) == 1
             and np.linalg.norm(ours.offsets[j]) > 1e-3]

    height = float(np.ptp(positions[0, :, 1]))                      # Y is up in every shared clip
    tolerance = 1e-4 * height
    worst = 0.0
    for frame in range(n):
        bpy.context.scene.frame_set(1 + frame)
        heads = np.array([armature.pose.bones[name].head for name in bone_names])
        worst = max(worst, float(np.abs(heads - positions[frame, joint_ids]).max()))
        for end, parent in tails:
            tail = np.array(armature.pose.bones[ours.names[parent]].tail)
            worst = max(worst, float(np.abs(tail - positions[frame, end]).max()))
    assert worst <= tolerance, f"{clip}: worst difference {worst:.3g} > {tolerance:.3g} (1e-4 of {height:.4g})"
