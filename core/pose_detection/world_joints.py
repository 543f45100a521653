"""BlazePose's metric 3D landmarks as the 17 canonical joints, in the camera's axes.

The landmark network answers, besides the picture's landmarks, 33 "world" landmarks in metres from
the centre between the hips (:mod:`.blazepose`).  They are the detector's own guess of the pose in
depth, worth keeping as a cue for what one view cannot tell (which end of a bone is nearer).  Here
they become the 17 joints exactly as the picture's landmarks do (:mod:`core.io.formats.mediapipe`:
the same landmarks, the same rules for the joints no landmark is, ``core/io/formats/_canonical.py``).

Axes: BlazePose's, after the region's rotation is undone, are x right, y down (as the picture) and
z away from the camera (smaller is nearer): the camera axes of :mod:`core.camera` (x right, y down,
z forward), so nothing is flipped.  Only the origin differs (the hips' centre, not the camera), and
the network sees a crop, so its depth axis is the crop's viewing direction: for a person seen off
the picture's centre it is turned from the camera's optical axis by the angle at which the person
is seen (a few degrees for most framings).
"""

from __future__ import annotations

import numpy as np

from ..io.formats._canonical import DERIVED
from ..io.formats.keypoint_sets import MEDIAPIPE_33
from ..skeleton import JOINT_INDEX, N_JOINTS


def world_joints(world: np.ndarray) -> np.ndarray:
    """(F, 17, 3) metres in :data:`core.skeleton.JOINTS` order from (F, 33, 3) world landmarks; NaN where
    a landmark a joint needs is NaN (a frame without a person)."""
    world = np.asarray(world, dtype=float).reshape(-1, len(MEDIAPIPE_33), 3)
    points = {name: world[:, k] for k, name in enumerate(MEDIAPIPE_33) if name is not None}
    for joint, recipe in DERIVED.items():
        if joint not in points:
            points[joint] = sum(w * points[name] for name, w in recipe)
    out = np.full((world.shape[0], N_JOINTS, 3), np.nan)
    for name, idx in JOINT_INDEX.items():
        out[:, idx] = points[name]
    return out
