"""Scenes the retargeting tests share: a take of the built-in walk and a Mixamo-style character rig."""

from __future__ import annotations

import numpy as np

N_FRAMES = 90


def walk_take():
    """A take built from the truth of the built-in walk (so the source motion is known exactly)."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=N_FRAMES), kinds=("pan",), seed=3)
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    scene_data.store_estimate(scene, truth_as_estimate(truth))
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    scene.monoskel.height_m = 1.75
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    return scene


#: Mixamo name (after the prefix and side) -> Unreal mannequin name pattern ({s}: l or r).
UNREAL_NAMES = {"Hips": "pelvis", "Spine": "spine_01", "Spine2": "spine_03", "Neck": "neck_01", "Head": "head",
                "UpLeg": "thigh_{s}", "Leg": "calf_{s}", "Foot": "foot_{s}", "Shoulder": "clavicle_{s}",
                "Arm": "upperarm_{s}", "ForeArm": "lowerarm_{s}", "Hand": "hand_{s}", "HandIndex1": "index_01_{s}"}


def unreal_name(mixamo: str) -> str:
    """The Unreal mannequin's name for a bone of :func:`mixamo_rig`."""
    base = mixamo.removeprefix("mixamorig:")
    for side, s in (("Left", "l"), ("Right", "r")):
        if base.startswith(side):
            return UNREAL_NAMES[base[len(side):]].format(s=s)
    return UNREAL_NAMES[base]


def mixamo_rig(scene, height_cm=180.0, arm_drop_deg=40.0, *, unreal=False):
    """A Mixamo-named armature in cm at 0.01 scale: A-pose arms, rolls all different, Euler legs.

    ``unreal``: the same body with the Unreal mannequin's bone names, facing +Y as the mannequin
    does in Blender.
    """
    import bpy

    from monoskel.core.skeleton import CLASSES
    from monoskel.core.synthetic.procedural import adult_class_lengths

    c = dict(zip(CLASSES, adult_class_lengths(height_cm / 100.0) * 100.0))
    p = {"hips": np.array([0.0, 0.0, 0.039 * height_cm + c["shank"] + c["thigh"]])}
    p["spine"] = p["hips"] + [0, 0.5, c["lower_spine"]]
    p["chest"] = p["spine"] + [0, 0.5, c["upper_spine"]]
    p["neck"] = p["chest"] + [0, -0.5, c["neck"]]
    p["head"] = p["neck"] + [0, 0, 0.4 * c["head"]]
    p["top"] = p["neck"] + [0, 0, c["head"]]
    a = np.radians(arm_drop_deg)
    for s, sign in (("L", 1.0), ("R", -1.0)):
        p[f"hip{s}"] = p["hips"] + [sign * c["hip"], 0, 0]
        p[f"knee{s}"] = p[f"hip{s}"] + [0, -1.0, -c["thigh"]]
        p[f"ankle{s}"] = p[f"hip{s}"] + [0, 0, -c["thigh"] - c["shank"]]
        p[f"toe{s}"] = p[f"ankle{s}"] + [0, -13.0, -6.0]
        p[f"shoulder{s}"] = p["chest"] + [sign * c["clavicle"], 0, 0]
        d = np.array([sign * np.cos(a), 0, -np.sin(a)])
        p[f"elbow{s}"] = p[f"shoulder{s}"] + d * c["upper_arm"]
        p[f"wrist{s}"] = p[f"elbow{s}"] + d * c["forearm"]
        p[f"finger{s}"] = p[f"wrist{s}"] + d * 9.0
    m = "mixamorig:"
    bones = [(m + "Hips", "hips", "spine", None), (m + "Spine", "spine", "chest", m + "Hips"),
             (m + "Spine2", "chest", "neck", m + "Spine"), (m + "Neck", "neck", "head", m + "Spine2"),
             (m + "Head", "head", "top", m + "Neck")]
    for s, side in (("L", "Left"), ("R", "Right")):
        bones += [(f"{m}{side}UpLeg", f"hip{s}", f"knee{s}", m + "Hips"),
                  (f"{m}{side}Leg", f"knee{s}", f"ankle{s}", f"{m}{side}UpLeg"),
                  (f"{m}{side}Foot", f"ankle{s}", f"toe{s}", f"{m}{side}Leg"),
                  (f"{m}{side}Shoulder", "chest", f"shoulder{s}", m + "Spine2"),
                  (f"{m}{side}Arm", f"shoulder{s}", f"elbow{s}", f"{m}{side}Shoulder"),
                  (f"{m}{side}ForeArm", f"elbow{s}", f"wrist{s}", f"{m}{side}Arm"),
                  (f"{m}{side}Hand", f"wrist{s}", f"finger{s}", f"{m}{side}ForeArm"),
                  (f"{m}{side}HandIndex1", f"wrist{s}", f"finger{s}", f"{m}{side}Hand")]
    if unreal:
        p = {k: v * [-1.0, -1.0, 1.0] for k, v in p.items()}          # turned to face +Y
        bones = [(unreal_name(n), h, t, unreal_name(par) if par else None) for n, h, t, par in bones]
    arm = bpy.data.armatures.new("Character")
    obj = bpy.data.objects.new("Character", arm)
    scene.collection.objects.link(obj)
    obj.scale = (0.01, 0.01, 0.01)
    obj.location = (2.0, 0.0, 0.0)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    for i, (name, head, tail, parent) in enumerate(bones):
        eb = arm.edit_bones.new(name)
        eb.head, eb.tail, eb.roll = p[head], p[tail], 0.37 * i
        if parent:
            eb.parent = arm.edit_bones[parent]
    bpy.ops.object.mode_set(mode="OBJECT")
    for pb in obj.pose.bones:
        if pb.name.endswith(("UpLeg", "Leg")) or pb.name.startswith(("thigh_", "calf_")):
            pb.rotation_mode = "XYZ"
    return obj


