"""The armature: 16 named bones in a T-pose, and pose keys that follow 3D joints.

Rest pose (documented for retargeting tools such as Rigify's or Mixamo-style
retargeters, which accept a T-pose): Z up, the figure faces -Y (Blender's
front view looks at its face), its left side is +X, it stands with the soles
on z = 0, legs straight down, arms straight out sideways, spine, neck and
head straight up.  The ankle joint sits at
:data:`core.skeleton.ANKLE_HEIGHT_FRACTION` of the height above the floor.

Hierarchy: ``spine_lower`` (pelvis to spine) is the root and carries the
translation; ``hip.L``/``hip.R`` (pelvis to hip joint) hang off it
unconnected; everything else chains as the canonical skeleton does.  Every
bone's local Z axis points to the figure's front in the rest pose.

Pose keys: for every frame with 3D joints, each bone is swung from the
direction its parent carries it in to the observed direction (the smallest
rotation, so a bone never twists about its own axis relative to its parent);
the root gets its full orientation from the spine direction and the hip line.
Posed bone heads then land on the observed joints whenever the observed
segment lengths equal the bone lengths (a rigid figure).
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Vector
from scipy.spatial.transform import Rotation

from ..core.skeleton import ANKLE_HEIGHT_FRACTION, CLASS_INDEX, JOINT_INDEX, N_JOINTS, standing_height
from . import compat

#: (bone name, head joint, tail joint, parent bone) — the single naming table of the rig.
BONES: tuple[tuple[str, str, str, str | None], ...] = (
    ("spine_lower", "pelvis", "spine", None),
    ("spine_upper", "spine", "thorax", "spine_lower"),
    ("neck", "thorax", "neck", "spine_upper"),
    ("head", "neck", "head", "neck"),
    ("hip.L", "pelvis", "l_hip", "spine_lower"),
    ("thigh.L", "l_hip", "l_knee", "hip.L"),
    ("shin.L", "l_knee", "l_ankle", "thigh.L"),
    ("hip.R", "pelvis", "r_hip", "spine_lower"),
    ("thigh.R", "r_hip", "r_knee", "hip.R"),
    ("shin.R", "r_knee", "r_ankle", "thigh.R"),
    ("clavicle.L", "thorax", "l_shoulder", "spine_upper"),
    ("upper_arm.L", "l_shoulder", "l_elbow", "clavicle.L"),
    ("forearm.L", "l_elbow", "l_wrist", "upper_arm.L"),
    ("clavicle.R", "thorax", "r_shoulder", "spine_upper"),
    ("upper_arm.R", "r_shoulder", "r_elbow", "clavicle.R"),
    ("forearm.R", "r_elbow", "r_wrist", "upper_arm.R"),
)
ROOT_BONE = BONES[0][0]
#: Bone name whose *tail* is each joint (pelvis: the root bone's head).
BONE_FOR_JOINT: dict[str, str] = {tail: name for name, _, tail, _ in BONES}


def rest_joints(class_lengths: np.ndarray) -> np.ndarray:
    """The 17 joints (17, 3) of the T-pose for class lengths (10,), Z up, soles on z = 0."""
    c = {name: float(class_lengths[i]) for name, i in CLASS_INDEX.items()}
    height = float(standing_height(np.asarray(class_lengths, dtype=float)))
    pelvis_z = ANKLE_HEIGHT_FRACTION * height + c["shank"] + c["thigh"]
    p = np.zeros((N_JOINTS, 3))

    def put(joint, parent, offset):
        p[JOINT_INDEX[joint]] = p[JOINT_INDEX[parent]] + np.asarray(offset, dtype=float)

    p[JOINT_INDEX["pelvis"]] = (0.0, 0.0, pelvis_z)
    put("spine", "pelvis", (0, 0, c["lower_spine"]))
    put("thorax", "spine", (0, 0, c["upper_spine"]))
    put("neck", "thorax", (0, 0, c["neck"]))
    put("head", "neck", (0, 0, c["head"]))
    for side, sign in (("l", 1.0), ("r", -1.0)):
        put(f"{side}_hip", "pelvis", (sign * c["hip"], 0, 0))
        put(f"{side}_knee", f"{side}_hip", (0, 0, -c["thigh"]))
        put(f"{side}_ankle", f"{side}_knee", (0, 0, -c["shank"]))
        put(f"{side}_shoulder", "thorax", (sign * c["clavicle"], 0, 0))
        put(f"{side}_elbow", f"{side}_shoulder", (sign * c["upper_arm"], 0, 0))
        put(f"{side}_wrist", f"{side}_elbow", (sign * c["forearm"], 0, 0))
    return p


def create_armature(scene, class_lengths: np.ndarray, name: str, created: list):
    """Armature object in the T-pose, linked to ``scene``; appends what it creates to ``created``."""
    joints = rest_joints(class_lengths)
    arm = bpy.data.armatures.new(name)
    created.append(arm)
    obj = bpy.data.objects.new(name, arm)
    created.append(obj)
    scene.collection.objects.link(obj)
    arm.display_type = 'STICK'
    obj.show_in_front = True

    # Edit bones need edit mode on an active object; do it with a context override so it
    # also works headless and from any editor.
    view_layer = scene.view_layers[0]
    with bpy.context.temp_override(scene=scene, view_layer=view_layer, active_object=obj, object=obj,
                                   selected_objects=[obj], selected_editable_objects=[obj]):
        previous_active = view_layer.objects.active
        view_layer.objects.active = obj
        bpy.ops.object.mode_set(mode='EDIT')
        try:
            edit = arm.edit_bones
            for bone_name, head, tail, parent in BONES:
                eb = edit.new(bone_name)
                eb.head = Vector(joints[JOINT_INDEX[head]])
                eb.tail = Vector(joints[JOINT_INDEX[tail]])
                eb.align_roll(Vector((0.0, -1.0, 0.0)))  # local Z to the figure's front
                if parent is not None:
                    eb.parent = edit[parent]
                    eb.use_connect = (edit[parent].tail - eb.head).length < 1e-9
        finally:
            bpy.ops.object.mode_set(mode='OBJECT')
            view_layer.objects.active = previous_active
    for pb in obj.pose.bones:
        pb.rotation_mode = 'QUATERNION'
    return obj


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def _swing(from_dir: np.ndarray, to_dir: np.ndarray, fallback_axis: np.ndarray) -> np.ndarray:
    """Smallest rotations (n, 3, 3) taking unit vectors ``from_dir`` to ``to_dir`` (n, 3)."""
    cross = np.cross(from_dir, to_dir)
    sin = np.linalg.norm(cross, axis=-1)
    cos = np.einsum("ni,ni->n", from_dir, to_dir)
    axis = np.where((sin > 1e-9)[:, None], cross / np.maximum(sin, 1e-12)[:, None], fallback_axis)
    angle = np.arctan2(sin, cos)
    return Rotation.from_rotvec(axis * angle[:, None]).as_matrix()


def pose_from_joints(obj, joints: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Root location (n, 3) and per-bone local quaternions (n, 4; w, x, y, z) for joints (n, 17, 3).

    ``joints`` are in the armature object's space.  Uses the rest matrices
    Blender actually built, so the result is exact for this armature.
    """
    n = joints.shape[0]
    bones = obj.data.bones
    rest = {b.name: np.array(b.matrix_local, dtype=float) for b in bones}
    rest_rot = {k: m[:3, :3] for k, m in rest.items()}
    world: dict[str, np.ndarray] = {}
    local: dict[str, np.ndarray] = {}

    def j(name):
        return joints[:, JOINT_INDEX[name]]

    # Root: full orientation from the spine direction (bone axis) and the hip line (lateral).
    up = _unit(j("spine") - j("pelvis"))
    lateral = j("l_hip") - j("r_hip")
    lateral = lateral - np.einsum("ni,ni->n", lateral, up)[:, None] * up
    lateral = _unit(lateral)
    observed = np.stack([lateral, up, np.cross(lateral, up)], axis=-1)           # columns
    rest_j = {name: np.array(bones[BONE_FOR_JOINT[name]].tail_local) for name in ("spine", "l_hip", "r_hip")}
    rest_j["pelvis"] = np.array(bones[ROOT_BONE].head_local)
    up_r = _unit(rest_j["spine"] - rest_j["pelvis"])
    lat_r = rest_j["l_hip"] - rest_j["r_hip"]
    lat_r = _unit(lat_r - lat_r.dot(up_r) * up_r)
    rest_frame = np.stack([lat_r, up_r, np.cross(lat_r, up_r)], axis=-1)
    world[ROOT_BONE] = observed @ rest_frame.T @ rest_rot[ROOT_BONE]
    local[ROOT_BONE] = np.swapaxes(rest_rot[ROOT_BONE], -1, -2) @ world[ROOT_BONE]

    for name, head, tail, parent in BONES[1:]:
        carried = world[parent] @ rest_rot[parent].T @ rest_rot[name]            # (n, 3, 3)
        target = _unit(j(tail) - j(head))
        swing = _swing(carried[:, :, 1], target, carried[:, :, 0])
        world[name] = swing @ carried
        local[name] = np.swapaxes(carried, -1, -2) @ world[name]

    quats = {}
    for name, mats in local.items():
        xyzw = Rotation.from_matrix(mats).as_quat()
        q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
        if n > 1:  # keep neighbouring keys in the same hemisphere so interpolation takes the short way
            flips = np.sign(np.einsum("ni,ni->n", q[1:], q[:-1]))
            flips[flips == 0] = 1.0
            q[1:] *= np.cumprod(flips)[:, None]
        quats[name] = q
    root_head = np.array(bones[ROOT_BONE].head_local)
    location = (j("pelvis") - root_head) @ rest_rot[ROOT_BONE]                  # R^T (p - h) per row
    return location, quats


def key_pose(obj, joints: np.ndarray, frames: np.ndarray, created: list) -> None:
    """Key the root location and every bone's quaternion at ``frames`` from joints (n, 17, 3)."""
    location, quats = pose_from_joints(obj, joints)
    action, made = compat.ensure_action(obj, f"{obj.name}Action")
    if made:
        created.append(action)
    fcurves = compat.ensure_fcurves(obj)
    root_path = f'pose.bones["{ROOT_BONE}"]'
    for axis in range(3):
        compat.set_keys(fcurves, f"{root_path}.location", axis, frames, location[:, axis], group=ROOT_BONE)
    for name, _, _, _ in BONES:
        path = f'pose.bones["{name}"].rotation_quaternion'
        for axis in range(4):
            compat.set_keys(fcurves, path, axis, frames, quats[name][:, axis], group=name)
