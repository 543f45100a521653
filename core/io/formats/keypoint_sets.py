"""Keypoint layouts of the supported detectors, translated to the shared vocabulary.

Each tuple lists, in the detector's own index order, the vocabulary name a
keypoint becomes (see :mod:`._canonical`) or None when it is not used (feet,
hands, mouth ...).  Left/right always mean the *person's* left/right, as in
every one of these detectors.
"""

from __future__ import annotations

#: COCO-17 (COCO keypoint task, most detectors' "coco" output).
COCO_17: tuple[str | None, ...] = (
    "nose", "l_eye", "r_eye", "l_ear", "r_ear",
    "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist",
    "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle",
)
COCO_17_NAMES: tuple[str, ...] = (
    "nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip",
    "left_knee", "right_knee", "left_ankle", "right_ankle",
)

#: OpenPose COCO-18.  Its "Neck" is the shoulders' midpoint by construction, so it is the canonical thorax.
OPENPOSE_COCO_18: tuple[str | None, ...] = (
    "nose", "thorax", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist",
    "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "r_eye", "l_eye", "r_ear", "l_ear",
)

#: OpenPose BODY_25: COCO-18 plus MidHip (the canonical pelvis) and six foot points (unused).
OPENPOSE_BODY_25: tuple[str | None, ...] = (
    "nose", "thorax", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist",
    "pelvis", "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "r_eye", "l_eye", "r_ear", "l_ear",
    None, None, None, None, None, None,
)

#: MediaPipe Pose landmark names, index order (33).
MEDIAPIPE_NAMES: tuple[str, ...] = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
    "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky",
    "left_index", "right_index", "left_thumb", "right_thumb", "left_hip", "right_hip",
    "left_knee", "right_knee", "left_ankle", "right_ankle", "left_heel", "right_heel",
    "left_foot_index", "right_foot_index",
)
_MEDIAPIPE_USED = {
    "nose": "nose", "left_eye": "l_eye", "right_eye": "r_eye", "left_ear": "l_ear", "right_ear": "r_ear",
    "left_shoulder": "l_shoulder", "right_shoulder": "r_shoulder", "left_elbow": "l_elbow",
    "right_elbow": "r_elbow", "left_wrist": "l_wrist", "right_wrist": "r_wrist", "left_hip": "l_hip",
    "right_hip": "r_hip", "left_knee": "l_knee", "right_knee": "r_knee", "left_ankle": "l_ankle",
    "right_ankle": "r_ankle",
}
MEDIAPIPE_33: tuple[str | None, ...] = tuple(_MEDIAPIPE_USED.get(n) for n in MEDIAPIPE_NAMES)


def used(layout: tuple[str | None, ...]) -> tuple[list[int], list[str]]:
    """(indices, vocabulary names) of the keypoints of ``layout`` that are used."""
    idx = [i for i, name in enumerate(layout) if name is not None]
    return idx, [layout[i] for i in idx]
