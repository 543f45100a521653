"""Retargeting the estimated motion onto the animator's own rig.

``rig``: the target armature's rest pose as plain arrays.  ``bone_map``: which target bone plays which
part (hips, spine chain, neck, head, clavicles, arms, legs, feet), guessed from names and from the shape
of the chains.  ``solve``: per-frame bone rotations (and the root's location) that put the target's
segments along the source's, with two-bone IK so feet and hands land on the source's scaled
positions and planted feet stay put.  ``curves``: smoothing, rotation continuity, key reduction.
"""

from .bone_map import ROLES, BoneMapError, check_bone_map, guess_bone_map
from .rig import TargetRig
from .solve import RetargetResult, RetargetSettings, retarget

__all__ = ["ROLES", "BoneMapError", "RetargetResult", "RetargetSettings", "TargetRig", "check_bone_map",
           "guess_bone_map", "retarget"]
