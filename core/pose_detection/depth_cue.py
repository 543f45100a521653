"""Which end of each bone is nearer the camera, as the detector's own 3D guess says.

One picture cannot tell whether a bone leans towards the camera or away from it (Taylor's depth
ambiguity: both mirror poses project alike); the joint solve chooses per frame and bone.  BlazePose's
metric 3D joints (:attr:`core.tracks.Tracks.landmarks_3d`) were learnt from people, so they carry an
opinion on exactly that choice.  :func:`bone_depth_order` reads it out as a sign per frame and bone,
for the solve to weigh as a soft cue: an opinion, not a measurement (nothing here knows how often
the network is right, and a bone nearly parallel to the picture is left undecided).
"""

from __future__ import annotations

import numpy as np

#: A bone whose depth change is below this share of its 3D length (about 6 degrees out of the
#: picture's plane) gets no opinion (0): there a few centimetres of the network's depth error flip it.
MIN_SLANT = 0.1

NEARER, FARTHER, UNKNOWN = 1, -1, 0


def bone_depth_order(landmarks_3d, bones, *, min_slant: float = MIN_SLANT) -> np.ndarray:
    """(F, B) int8: +1 where the bone's child joint is nearer the camera than its parent, -1 where farther,
    0 where unknown (either joint missing, or the bone within ``min_slant`` of the picture's plane).

    ``landmarks_3d``: (F, J, 3) camera axes (z forward, away from the camera; any origin), NaN where
    missing, as :attr:`core.tracks.Tracks.landmarks_3d`.  ``bones``: (parent, child) joint index pairs,
    e.g. :data:`core.skeleton.SEGMENTS`.  (The joint solve's Taylor sign is the other way round: its +1
    puts the child on the far side, :func:`core.joint_solve.taylor.reconstruct`.)
    """
    pts = np.asarray(landmarks_3d, dtype=float)
    if pts.ndim != 3 or pts.shape[-1] != 3:
        raise ValueError(f"landmarks_3d must be shaped (frames, joints, 3), got {pts.shape}")
    pairs = np.asarray(bones, dtype=int).reshape(-1, 2)
    if pairs.size and (pairs.min() < 0 or pairs.max() >= pts.shape[1]):
        raise ValueError(f"bone joint indices must lie in 0..{pts.shape[1] - 1}")
    if not min_slant >= 0:
        raise ValueError(f"min_slant must be 0 or more, got {min_slant!r}")
    vec = pts[:, pairs[:, 1]] - pts[:, pairs[:, 0]]                      # (F, B, 3) parent -> child
    length = np.linalg.norm(vec, axis=-1)
    dz = vec[..., 2]
    known = np.isfinite(length) & (length > 0) & (np.abs(dz) > min_slant * np.where(np.isfinite(length), length, 0))
    out = np.where(dz < 0, NEARER, FARTHER)
    return np.where(known, out, UNKNOWN).astype(np.int8)
