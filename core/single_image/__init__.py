"""Taylor's single-image posing: a 3D pose from one photo or one frame of 2D joints.

:mod:`.family` builds Taylor's one-parameter family of poses (scaled orthographic, or perspective
with a focal length), :mod:`.signs` chooses the two-way depth sign of every segment, :mod:`.pose`
ties them together and reads/writes the ``skeleton-pose`` JSON; :mod:`.cli` is
``python -m core single-image``.
"""

from .pose import SEGMENT_NAMES, SinglePose, pose_from_image, read_pose_json, write_pose_json

__all__ = ["SEGMENT_NAMES", "SinglePose", "pose_from_image", "read_pose_json", "write_pose_json"]
