"""The canonical 17-joint skeleton every module speaks.

Joint names, the tree, the 16 segments and their 10 left/right-symmetric
length classes are fixed here and nowhere else.  A skeleton's *proportions*
are the 10 class lengths (left/right averaged) divided by their sum, as in
Peng & Li 2006, Table 1.
"""

from __future__ import annotations

import numpy as np

JOINTS: tuple[str, ...] = (
    "pelvis", "spine", "thorax", "neck", "head",
    "l_hip", "l_knee", "l_ankle",
    "r_hip", "r_knee", "r_ankle",
    "l_shoulder", "l_elbow", "l_wrist",
    "r_shoulder", "r_elbow", "r_wrist",
)
N_JOINTS = len(JOINTS)
JOINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(JOINTS)}

#: Parent joint index of every joint (-1 for the root, ``pelvis``).
PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3,
    0, 5, 6,
    0, 8, 9,
    2, 11, 12,
    2, 14, 15,
)

#: The 10 symmetric length classes, in Table-1 style order.
CLASSES: tuple[str, ...] = (
    "hip", "thigh", "shank", "lower_spine", "upper_spine",
    "neck", "head", "clavicle", "upper_arm", "forearm",
)
N_CLASSES = len(CLASSES)
CLASS_INDEX: dict[str, int] = {name: i for i, name in enumerate(CLASSES)}

#: Segments as (parent joint, child joint); one per non-root joint, in joint order.
SEGMENTS: tuple[tuple[int, int], ...] = tuple(
    (PARENTS[j], j) for j in range(N_JOINTS) if PARENTS[j] >= 0
)
N_SEGMENTS = len(SEGMENTS)

_CHILD_CLASS = {
    "spine": "lower_spine", "thorax": "upper_spine", "neck": "neck", "head": "head",
    "l_hip": "hip", "l_knee": "thigh", "l_ankle": "shank",
    "r_hip": "hip", "r_knee": "thigh", "r_ankle": "shank",
    "l_shoulder": "clavicle", "l_elbow": "upper_arm", "l_wrist": "forearm",
    "r_shoulder": "clavicle", "r_elbow": "upper_arm", "r_wrist": "forearm",
}
#: Class index of every segment (same order as :data:`SEGMENTS`).
SEGMENT_CLASS: tuple[int, ...] = tuple(CLASS_INDEX[_CHILD_CLASS[JOINTS[c]]] for _, c in SEGMENTS)

def _joint_levels() -> tuple[int, ...]:
    levels = [0] * N_JOINTS
    for j in range(1, N_JOINTS):  # parents precede children in JOINTS
        levels[j] = levels[PARENTS[j]] + 1
    return tuple(levels)


#: Depth of each joint in the tree (pelvis 0); Peng & Li estimate level by level.
JOINT_LEVEL: tuple[int, ...] = _joint_levels()

FEET = {"l": JOINT_INDEX["l_ankle"], "r": JOINT_INDEX["r_ankle"]}

#: The four limb chains, each from the body out (an occlusion hides one whole; a detector exchanges
#: a left one with its right twin).
LIMBS: dict[str, tuple[int, ...]] = {
    "l_arm": tuple(JOINT_INDEX[n] for n in ("l_shoulder", "l_elbow", "l_wrist")),
    "r_arm": tuple(JOINT_INDEX[n] for n in ("r_shoulder", "r_elbow", "r_wrist")),
    "l_leg": tuple(JOINT_INDEX[n] for n in ("l_hip", "l_knee", "l_ankle")),
    "r_leg": tuple(JOINT_INDEX[n] for n in ("r_hip", "r_knee", "r_ankle")),
}
#: Left/right pairs of limb chains: ``(left chain, right chain)``.
LIMB_PAIRS: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = {
    "legs": (LIMBS["l_leg"], LIMBS["r_leg"]),
    "arms": (LIMBS["l_arm"], LIMBS["r_arm"]),
}
KNEES = {"l": JOINT_INDEX["l_knee"], "r": JOINT_INDEX["r_knee"]}
#: Each joint's left/right twin (a midline joint is its own).
MIRROR: tuple[int, ...] = tuple(JOINT_INDEX.get({"l_": "r_", "r_": "l_"}.get(n[:2], "") + n[2:], j)
                                for j, n in enumerate(JOINTS))

#: Height of the ankle joint above the sole as a fraction of stature
#: (anthropometric tables, ~3.9 %).  Used to turn the straight ankle-to-head
#: chain into a standing height.
ANKLE_HEIGHT_FRACTION = 0.039


def segment_lengths(joints: np.ndarray) -> np.ndarray:
    """Length of each of the 16 segments for joints shaped (..., 17, 3)."""
    joints = np.asarray(joints, dtype=float)
    parents = np.array([p for p, _ in SEGMENTS])
    children = np.array([c for _, c in SEGMENTS])
    return np.linalg.norm(joints[..., children, :] - joints[..., parents, :], axis=-1)


def class_lengths_from_segments(seg_lengths: np.ndarray) -> np.ndarray:
    """Average segment lengths (..., 16) into the 10 class lengths (..., 10)."""
    seg_lengths = np.asarray(seg_lengths, dtype=float)
    out = np.zeros(seg_lengths.shape[:-1] + (N_CLASSES,))
    count = np.zeros(N_CLASSES)
    for s, c in enumerate(SEGMENT_CLASS):
        out[..., c] += seg_lengths[..., s]
        count[c] += 1
    return out / count


def segment_lengths_from_classes(class_lengths: np.ndarray) -> np.ndarray:
    """Expand 10 class lengths (..., 10) to the 16 segment lengths (..., 16)."""
    class_lengths = np.asarray(class_lengths, dtype=float)
    return class_lengths[..., list(SEGMENT_CLASS)]


def proportions(class_lengths: np.ndarray) -> np.ndarray:
    """Normalise class lengths so they sum to 1 (Peng & Li's proportions)."""
    class_lengths = np.asarray(class_lengths, dtype=float)
    return class_lengths / class_lengths.sum(axis=-1, keepdims=True)


def proportions_dict(values: np.ndarray) -> dict[str, float]:
    """Class-name -> proportion mapping, the shape used in JSON files."""
    p = proportions(values)
    return {name: float(p[i]) for i, name in enumerate(CLASSES)}


def proportions_array(mapping: dict[str, float]) -> np.ndarray:
    """Inverse of :func:`proportions_dict` (order of :data:`CLASSES`)."""
    return np.array([float(mapping[name]) for name in CLASSES])


#: Class indices of the ankle-to-head-top chain that makes up stature (with the ankle height).
HEIGHT_CLASSES = [CLASS_INDEX[n] for n in ("shank", "thigh", "lower_spine", "upper_spine", "neck", "head")]


def standing_height(class_lengths: np.ndarray) -> np.ndarray:
    """Stature implied by class lengths: ankle-to-head chain plus the ankle height.

    The chain is shank + thigh + lower_spine + upper_spine + neck + head (the
    head segment ends at the head top); the ankle sits
    :data:`ANKLE_HEIGHT_FRACTION` of stature above the floor.
    """
    c = np.asarray(class_lengths, dtype=float)
    return c[..., HEIGHT_CLASSES].sum(axis=-1) / (1.0 - ANKLE_HEIGHT_FRACTION)


def class_lengths_for_height(props: np.ndarray, height_m: float) -> np.ndarray:
    """Class lengths in metres for proportions scaled to a standing height."""
    props = np.asarray(props, dtype=float)
    return props * (height_m / standing_height(props))
