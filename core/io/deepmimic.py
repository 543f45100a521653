"""DeepMimic motion files as BVH: motion capture retargeted onto a simulated character, read for training.

Why: physics-animation projects publish motion capture retargeted onto DeepMimic's humanoid (a character
file of joints with fixed offsets, and motion files of per-frame joint rotations), among them CMU clips that
no BVH collection within reach holds (runs over obstacles, flips, acrobatics, cartwheels). Written out as
BVH, they go through the same reader, mapping and training commands as any other capture
(``python -m core deepmimic-to-bvh``).

The formats (both JSON):

* the character: ``{"Skeleton": {"Joints": [{"ID", "Name", "Type", "Parent", "AttachX", "AttachY",
  "AttachZ", ...}, ...]}, ...}``, a joint's place in its parent's frame in metres, y up; ``Type`` is
  ``none`` (the root), ``spherical`` (a quaternion in the motion), ``revolute`` (one angle about the
  joint's z axis) or ``fixed`` (nothing in the motion);
* the motion: ``{"Frames": [[duration, root x, y, z, root quaternion w, x, y, z, then each non-root,
  non-fixed joint in the character's order: a quaternion (w, x, y, z) or an angle in radians], ...]}``.

The BVH keeps the character's joints, names them the way the BVH mapping reads sides (``Left*`` /
``Right*`` for ``left_*`` / ``right_*``) and adds End Sites where the character's bodies end (the head's
top, the toes, the hands' ends), from the character's body shapes when it has them.
"""

from __future__ import annotations

import json
import os

import numpy as np

from ..errors import InputError
from .bvh import Bvh, make_bvh

#: DeepMimic character joint types and how many motion numbers each takes.
_TYPE_SIZE = {"none": 7, "spherical": 4, "revolute": 1, "fixed": 0}
#: BVH names for DeepMimic humanoid joint names (sides in the form the BVH mapping reads).
_NAMES = {"root": "Hips", "chest": "Chest", "neck": "Neck", "hip": "UpLeg", "knee": "Leg", "ankle": "Foot",
          "shoulder": "Arm", "elbow": "ForeArm", "wrist": "Hand"}
#: End Sites by the DeepMimic name of their joint: a fallback offset (metres) used when the character
#: has no body shape to take it from.
_ENDS = {"neck": (0.0, 0.27, 0.0), "ankle": (0.13, -0.05, 0.0), "wrist": (0.0, -0.08, 0.0)}
#: The BVH is written in centimetres, as most capture files are.
_CM = 100.0


def _bvh_name(name: str) -> str:
    for side, prefix in (("left_", "Left"), ("right_", "Right")):
        if name.startswith(side):
            return prefix + _NAMES.get(name[len(side):], name[len(side):].title())
    return _NAMES.get(name, name.title())


def _why(exc: Exception) -> str:
    """A reading error in a few words."""
    if isinstance(exc, KeyError):
        return f"no {exc.args[0]!r} in it"
    if isinstance(exc, OSError):
        return exc.strerror or str(exc)
    return str(exc)


def read_character(path: str) -> list[dict]:
    """The character file's joints in parent-first order, checked (an :class:`InputError` if it is not one)."""
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
        joints = sorted(doc["Skeleton"]["Joints"], key=lambda j: int(j["ID"]))
        bodies = {b["Name"]: b for b in doc.get("BodyDefs", [])}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a DeepMimic character file ({_why(exc)})") from None
    for k, j in enumerate(joints):
        if int(j["ID"]) != k or int(j["Parent"]) >= k or j.get("Type") not in _TYPE_SIZE:
            raise InputError(f"{path}: joint {j.get('Name')!r} is out of order or of an unknown type")
        j["body"] = bodies.get(j["Name"])
    return joints


def _end_offset(joint: dict) -> np.ndarray | None:
    """Where the body hanging on ``joint`` ends, in the joint's frame (None: no End Site there)."""
    kind = joint["Name"].split("_")[-1]
    if kind not in _ENDS:
        return None
    body = joint.get("body")
    if body is not None and kind == "ankle" and body.get("Shape") == "box":
        # the foot's box: its front bottom edge is the toes
        return np.array([float(body["AttachX"]) + 0.5 * float(body["Param0"]),
                         float(body["AttachY"]) - 0.5 * float(body["Param1"]), 0.0])
    if body is not None and kind == "neck" and body.get("Shape") == "sphere":
        return np.array([0.0, float(body["AttachY"]) + 0.5 * float(body["Param0"]), 0.0])
    return np.array(_ENDS[kind])


def _quat_matrices(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of (..., 4) quaternions (w, x, y, z), normalised first."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _euler_zxy_deg(R: np.ndarray) -> np.ndarray:
    """(z, x, y) angles in degrees with ``R = Rz(z) Rx(x) Ry(y)``, the order of the BVH's ``ZXY`` channels."""
    x = np.arcsin(np.clip(R[..., 2, 1], -1.0, 1.0))
    z = np.arctan2(-R[..., 0, 1], R[..., 1, 1])
    y = np.arctan2(-R[..., 2, 0], R[..., 2, 2])
    return np.degrees(np.stack([z, x, y], -1))


def _local_rotations(joints: list[dict], frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(root positions (F, 3) in metres, each joint's rotation in its parent's frame (F, J, 3, 3)) of the
    motion's frames (F, 1 + numbers), the duration column included, as many numbers as the character takes
    (checked by :func:`motion_to_bvh`)."""
    n = frames.shape[0]
    R = np.broadcast_to(np.eye(3), (n, len(joints), 3, 3)).copy()
    col = 1
    root = np.zeros((n, 3))
    for k, j in enumerate(joints):
        size = _TYPE_SIZE[j["Type"]]
        vals = frames[:, col:col + size]
        if j["Type"] == "none":
            root, R[:, k] = vals[:, :3], _quat_matrices(vals[:, 3:7])
        elif j["Type"] == "spherical":
            R[:, k] = _quat_matrices(vals)
        elif j["Type"] == "revolute":
            c, s = np.cos(vals[:, 0]), np.sin(vals[:, 0])
            R[:, k, 0, 0], R[:, k, 0, 1], R[:, k, 1, 0], R[:, k, 1, 1] = c, -s, s, c
        col += size
    return root, R


def motion_to_bvh(joints: list[dict], motion_path: str) -> Bvh:
    """The DeepMimic motion file ``motion_path`` on the character ``joints`` (:func:`read_character`) as a
    :class:`Bvh` in centimetres at the motion's own frame time."""
    try:
        with open(motion_path, encoding="utf-8") as fh:
            frames = np.asarray(json.load(fh)["Frames"], dtype=float)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{motion_path}: not a DeepMimic motion file ({_why(exc)})") from None
    if frames.ndim != 2 or frames.shape[0] < 2:
        raise InputError(f"{motion_path}: a DeepMimic motion needs at least two frames of numbers")
    need = 1 + sum(_TYPE_SIZE[j["Type"]] for j in joints)
    if frames.shape[1] != need:
        raise InputError(f"{motion_path}: {frames.shape[1]} numbers a frame, where the character needs {need}")
    root, R = _local_rotations(joints, frames)
    tree, channels = [], {}
    names = [_bvh_name(j["Name"]) for j in joints]
    for k, j in enumerate(joints):
        parent = int(j["Parent"])
        offset = np.array([float(j["AttachX"]), float(j["AttachY"]), float(j["AttachZ"])]) * _CM
        tree.append((names[k], names[parent] if parent >= 0 else None, tuple(offset)))
        angles = _euler_zxy_deg(R[:, k])
        channels[names[k]] = np.concatenate([root * _CM, angles], axis=1) if parent < 0 else angles
        end = _end_offset(j)
        if end is not None:
            tree.append((names[k] + "_End", names[k], tuple(end * _CM)))
    tree = _with_upper_chest(tree)
    frame_time = float(np.median(frames[:, 0]))
    if not frame_time > 0:
        raise InputError(f"{motion_path}: its frames' durations are not positive")
    tree = _depth_first(tree)
    zeros = np.zeros((frames.shape[0], 3))                 # a joint the character does not move
    motion = np.concatenate([channels.get(node[0], zeros) for node in tree if not node[0].endswith("_End")],
                            axis=1)
    return make_bvh(tree, motion, frame_time=frame_time, rotation_order="ZXY", path=os.path.abspath(motion_path))


def _with_upper_chest(tree: list[tuple]) -> list[tuple]:
    """``tree`` with a joint added where the two arms leave the trunk, carrying the arms and the neck.

    DeepMimic's humanoid hangs its arms on the chest joint, halfway up the trunk, 24 cm below the
    shoulders; a capture rig has a joint at the shoulders' height there (CMU's ``Spine1``), and the BVH
    mapping takes the joint where the arms branch as the thorax. Without one the humanoid's thorax would
    sit at mid-trunk and its clavicles would climb steeply to the shoulders: another trunk's geometry than
    the one a picture's shoulders and hips show. The added joint has no rotation of its own."""
    arms = [node for node in tree if node[0] in ("LeftArm", "RightArm")]
    if len(arms) != 2 or arms[0][1] != arms[1][1]:
        return tree
    chest = arms[0][1]
    at = (np.asarray(arms[0][2]) + np.asarray(arms[1][2])) / 2.0
    out = []
    for name, parent, offset in tree:
        if parent == chest and (name in ("LeftArm", "RightArm", "Neck")):
            parent, offset = "UpperChest", tuple(np.asarray(offset) - at)
        out.append((name, parent, offset))
        if name == chest:
            out.append(("UpperChest", chest, tuple(at)))
    return out


def _depth_first(tree: list[tuple]) -> list[tuple]:
    """``tree``'s nodes depth first, children in their listed order: the order BVH text nests joints in, and
    so the order of the motion's channels (a DeepMimic character lists the hips after the arms' chains
    have started elsewhere)."""
    children: dict[str | None, list[tuple]] = {}
    for node in tree:
        children.setdefault(node[1], []).append(node)
    out: list[tuple] = []

    def visit(parent):
        for node in children.get(parent, []):
            out.append(node)
            visit(node[0])

    visit(None)
    return out


def add_arguments(parser) -> None:
    parser.add_argument("motions", nargs="+", metavar="MOTION", help="DeepMimic motion files (JSON, .txt)")
    parser.add_argument("--character", required=True,
                        help="the DeepMimic character file the motions were made for (e.g. humanoid3d.txt)")
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for the BVH files (made if missing)")


def run(args) -> int:
    """``python -m core deepmimic-to-bvh``: each motion file to ``DIR/<its name>.bvh``."""
    from .bvh import format_bvh

    joints = read_character(args.character)
    os.makedirs(args.out, exist_ok=True)
    for path in args.motions:
        bvh = motion_to_bvh(joints, path)
        out = os.path.join(args.out, os.path.splitext(os.path.basename(path))[0] + ".bvh")
        with open(out, "w", encoding="utf-8") as fh:
            fh.write(format_bvh(bvh))
        print(f"{out}: {bvh.n_frames} frames at {bvh.fps:g} fps")
    return 0
