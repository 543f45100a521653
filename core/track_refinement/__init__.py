"""Joint tracks refined on the footage: a detector's positions fused with an image tracker's motion.

D'Apuzzo et al. (1999) follow body points through the frames with least-squares matching; a 2D pose
detector finds joints anew in every frame, with jitter and misses. :mod:`.fuse` combines the two for
one joint (the tracker for the motion between frames, the detector for where the joint is);
:mod:`.refine` plans the tracker's seeds and applies the fusion to all joints. The tracker runs in
Blender (:mod:`blender.track_refinement`); the core never reads images.
"""

from .fuse import FuseSettings, JointFusion, TrackedRun, fuse_joint
from .refine import DISAGREE_POLICIES, RefineReport, refine_tracks, seed_plan

__all__ = ["DISAGREE_POLICIES", "FuseSettings", "JointFusion", "RefineReport", "TrackedRun", "fuse_joint",
           "refine_tracks", "seed_plan"]
