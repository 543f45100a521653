"""Cleaning the solved 3D motion for an animator: planted feet held still (a smoothed root: off).

The joint solve (:mod:`core.joint_solve`) fits every frame's pose to the picture; what it leaves
is what a rig shows badly: ankles that slide while the foot stands, and a root that shakes along the
line of sight.  :func:`clean_motion` runs, in order:

1. :mod:`.root`: the figure's distance from the camera smoothed (its direction kept); off by default
   (measured no help, :attr:`CleanupSettings.root_sigma_s`);
2. :mod:`.contacts`: which ankle is planted, from the (smoothed) motion in world axes;
3. :mod:`.foot_lock`: each contact's ankle pinned to one place, the leg bent to reach it, eased in
   and out.

Bone lengths are kept throughout (the root moves the figure rigidly, the lock bends the leg).
:func:`core.estimate.estimate` runs it (:func:`clean_estimate`) on every estimate with 3D motion, at the
input's frame rate, after the solve and its second pass and before the self-check, which then measures
the reprojection of the cleaned motion (``motion_cleanup=None`` switches it off).

Beside it, the animator's own corrections, never run on their own: :mod:`.depth_flip`, one bone turned to
its other side in depth over a span of frames (*Flip Bone Depth*, ``python -m core flip-depth``), and
:mod:`.foot_plant`, one foot held still over a span of frames (*Plant Foot*, ``python -m core plant-foot``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .contacts import ContactSettings, detect_contacts
from .foot_lock import lock_feet
from .root import smooth_root_distance


@dataclass(frozen=True)
class CleanupSettings:
    contacts: ContactSettings = field(default_factory=ContactSettings)
    blend_s: float = 0.1              # the lock eases in and out over this time
    #: Gaussian smoothing (seconds) of the root's distance from the camera; 0, off: on the tune half of
    #: ``bench/motion_bench.py`` (5 clips x 3 draws x 4 scenarios) 0.05 s alone made the planted ankles faster,
    #: not slower (median |planted excess| paper / still / detector / background 116 / 123 / 995 / 37 -> 134 /
    #: 129 / 1000 / 71 mm/s), and the world jitter larger (docs/motion.md).
    root_sigma_s: float = 0.0
    lock_feet: bool = True


DEFAULT_CLEANUP = CleanupSettings()


def clean_motion(joints: np.ndarray, world_from_cam0: np.ndarray, fps: float, height_m: float,
                 settings: CleanupSettings = DEFAULT_CLEANUP) -> tuple[np.ndarray, dict]:
    """(cleaned joints (F, 17, 3) in frame-0 camera axes, report); ``world_from_cam0`` 4x4 gives the up
    direction (world Z) in which the ankles are judged low."""
    j = np.asarray(joints, dtype=float)
    report: dict = {}
    j, report["root_max_slide_m"] = smooth_root_distance(j, fps, settings.root_sigma_s)
    if settings.lock_feet:
        world = np.asarray(world_from_cam0, dtype=float)
        jw = j @ world[:3, :3].T + world[:3, 3]
        contacts = detect_contacts(jw, fps, height_m, settings.contacts)
        j, lock = lock_feet(j, contacts, fps, settings.blend_s)
        report.update(lock)
    return j, report


def clean_estimate(est, fps: float, settings: CleanupSettings = DEFAULT_CLEANUP) -> bool:
    """Clean ``est`` (a :class:`core.result.Estimate`) in place: its ``joints_3d`` replaced by
    :func:`clean_motion`'s, the report in ``diagnostics["motion_cleanup"]``.  An estimate without 3D
    joints on every frame or without ``world_from_cam0`` is left alone; returns whether it was cleaned."""
    world = est.diagnostics.get("world_from_cam0")
    if world is None or not est.frames or any(f.joints_3d is None for f in est.frames) or not fps > 0:
        return False
    joints = np.array([f.joints_3d for f in est.frames], dtype=float)
    height = float(est.height_m) if est.height_m else 1.75
    cleaned, report = clean_motion(joints, np.asarray(world, dtype=float), float(fps), height, settings)
    for f, j in zip(est.frames, cleaned, strict=True):
        f.joints_3d = j.tolist()
    est.diagnostics["motion_cleanup"] = report
    return True


__all__ = ["CleanupSettings", "ContactSettings", "DEFAULT_CLEANUP", "clean_estimate", "clean_motion",
           "detect_contacts"]
