"""A pose as the directions of its 16 bones in the body's own frame.

Why this frame: a depth sign guessed wrong turns one bone through the plane of the picture, and the
way to tell such a bone is where it points *relative to the body*: a knee bent forwards, a thigh
swung out sideways, an arm behind the back.  Where the person faces (the heading) and where the
camera stands say nothing about that, so both are taken out.  The frame is built from the body
alone, so it needs no floor or up direction, which the estimators know only after the solve:

* ``up``: the hips' midpoint to the thorax (the trunk), or a given up direction;
* ``left``: right hip to left hip, made perpendicular to ``up``;
* ``forward``: ``left x up`` (right-handed, as :func:`core.joint_solve.signs_dp._body_axes`).

Left and right stay apart (the left thigh's direction is features 0-2, the right thigh's 6-8), and no
mirror symmetry is folded in: a pose mirrored through the picture's plane is a reflection of the body, and
in this frame it shows as knees bending forwards and limbs on the wrong side, which the prior sees.

Everything works on *bone vectors* (..., 16, 3), child minus parent in :data:`core.skeleton.SEGMENTS`
order, so that a depth sign flipped on one bone is one negated coordinate of one vector.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import JOINT_INDEX, N_JOINTS, N_SEGMENTS, SEGMENTS

#: The bones the prior scores by default: the four limbs' upper and lower bones (thighs, shanks, upper
#: arms, forearms).  The trunk's, hips', clavicles', neck's and head's own directions are left out: where
#: a skeleton puts its pelvis, spine, clavicle and head joints is a convention of the capture's rig (the
#: CMU rig's pelvis sits behind its hips' midpoint, another's does not), so a prior trained on one rig
#: would find another rig's every pose unlikely (measured: ``docs/motion_prior.md``).  Their depth signs
#: still show, through the body frame they set.
LIMB_BONES: tuple[int, ...] = tuple(JOINT_INDEX[n] - 1 for n in (
    "l_knee", "l_ankle", "r_knee", "r_ankle", "l_elbow", "l_wrist", "r_elbow", "r_wrist"))
#: The legs' bones alone (thighs, shanks).
LEG_BONES: tuple[int, ...] = LIMB_BONES[:4]
ALL_BONES: tuple[int, ...] = tuple(range(N_SEGMENTS))
N_FEATURES = 3 * N_SEGMENTS
_P = np.array([p for p, _ in SEGMENTS])
_C = np.array([c for _, c in SEGMENTS])
# segment index = child joint index - 1 (parents precede children in core.skeleton.JOINTS)
_SEG = {name: JOINT_INDEX[name] - 1 for name in ("spine", "thorax", "l_hip", "r_hip")}


def bone_vectors(joints: np.ndarray) -> np.ndarray:
    """(..., 16, 3) child minus parent for joints (..., 17, 3)."""
    joints = np.asarray(joints, dtype=float)
    return joints[..., _C, :] - joints[..., _P, :]


def joints_from_bones(bones: np.ndarray, root: np.ndarray | None = None) -> np.ndarray:
    """(..., 17, 3) joints from bone vectors (..., 16, 3), the root at ``root`` (default the origin)."""
    bones = np.asarray(bones, dtype=float)
    out = np.zeros(bones.shape[:-2] + (N_JOINTS, 3))
    if root is not None:
        out[..., 0, :] = root
    for s, (p, c) in enumerate(SEGMENTS):          # parents precede children
        out[..., c, :] = out[..., p, :] + bones[..., s, :]
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def body_frame(bones: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
    """(..., 3, 3) rows ``left, up, forward`` of the body's frame for bone vectors (..., 16, 3)."""
    left = bones[..., _SEG["l_hip"], :] - bones[..., _SEG["r_hip"], :]
    if up is None:       # the hips' midpoint to the thorax (the pelvis joint's place is the rig's convention)
        up = (bones[..., _SEG["spine"], :] + bones[..., _SEG["thorax"], :]
              - 0.5 * (bones[..., _SEG["l_hip"], :] + bones[..., _SEG["r_hip"], :]))
    u = _unit(np.broadcast_to(up, left.shape))
    x = _unit(left - np.sum(left * u, axis=-1, keepdims=True) * u)
    z = np.cross(x, u)
    return np.stack([x, u, z], axis=-2)


def features_from_bones(bones: np.ndarray, up: np.ndarray | None = None,
                        which: tuple[int, ...] = LIMB_BONES) -> np.ndarray:
    """(..., 3 x len(which)) unit directions of the bones ``which`` in the body's frame (:func:`body_frame`)."""
    bones = np.asarray(bones, dtype=float)
    frame = body_frame(bones, up)
    local = np.einsum("...ab,...sb->...sa", frame, _unit(bones[..., list(which), :]))
    return local.reshape(local.shape[:-2] + (3 * len(which),))


def pose_features(joints: np.ndarray, up: np.ndarray | None = None, which: tuple[int, ...] = LIMB_BONES) -> np.ndarray:
    """(..., 3 x len(which)) features of joints (..., 17, 3) (module docstring)."""
    return features_from_bones(bone_vectors(joints), up, which)


def mirrored_left_right(joints: np.ndarray) -> np.ndarray:
    """The same body reflected through its own sagittal plane with left and right names exchanged.

    A real pose mirrored *and relabelled* is again a pose a person can take (the left hand dribbling
    instead of the right), so training adds it; it is not the depth mirror the prior must reject
    (that one reflects the body and keeps its names)."""
    from ..skeleton import MIRROR

    joints = np.asarray(joints, dtype=float)
    frame = body_frame(bone_vectors(joints))                   # (F, 3, 3)
    root = joints[..., :1, :]
    local = np.einsum("...ab,...jb->...ja", frame, joints - root)
    local[..., 0] *= -1.0
    back = np.einsum("...ba,...jb->...ja", frame, local) + root
    return back[..., list(MIRROR), :]
