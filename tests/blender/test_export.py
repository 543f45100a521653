"""Export through Blender's own BVH and FBX exporters, headless, and read the files back."""

import bpy
import pytest


def _built(scene, n_frames=12):
    from monoskel.blender import build
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), seed=1)
    return build.build_all(scene, truth_as_estimate(truth), tracks, height_m=1.75)


def test_bvh_export_reimports_with_every_frame_and_bone(empty_scene, tmp_path):
    from monoskel.blender import build, export

    out = _built(empty_scene, n_frames=12)
    path = tmp_path / "motion.bvh"
    export.export_bvh(empty_scene, out["armature"], path)
    text = path.read_text()
    assert "Frames: 12" in text
    assert text.count("CHANNELS 6") == 1  # only the root carries translation
    before = set(bpy.data.objects)
    bpy.ops.import_anim.bvh(filepath=str(path))
    (imported,) = set(bpy.data.objects) - before
    assert imported.type == 'ARMATURE'
    assert {b.name for b in imported.data.bones} == {name for name, *_ in build.BONES}
    start, end = imported.animation_data.action.frame_range
    assert int(round(end - start)) + 1 == 12


def test_fbx_export_carries_armature_and_camera(empty_scene, tmp_path):
    from monoskel.blender import export

    out = _built(empty_scene, n_frames=8)
    path = tmp_path / "scene.fbx"
    export.export_fbx(empty_scene, [out["armature"], out["camera"]], path)
    assert path.read_bytes().startswith(b"Kaydara FBX Binary")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.fbx(filepath=str(path))
    kinds = sorted(o.type for o in bpy.data.objects)
    assert "ARMATURE" in kinds and "CAMERA" in kinds
    arm = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
    assert len(arm.data.bones) == 16


def test_export_to_a_missing_folder_is_an_input_error(empty_scene, tmp_path):
    from monoskel.blender import export
    from monoskel.core.errors import InputError

    out = _built(empty_scene, n_frames=4)
    with pytest.raises(InputError, match="does not exist"):
        export.export_bvh(empty_scene, out["armature"], tmp_path / "nope" / "x.bvh")
