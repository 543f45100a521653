"""Refined joint tracks: every joint's detector path fused with the tracker's runs (:mod:`.fuse`).

The tracker itself is outside the core (Blender's, in :mod:`blender.track_refinement`); the core
plans where it is seeded (:func:`seed_plan`, :func:`carried_seeds` for joints whose detector position
is missing or a miss) and fuses what it returns (:func:`refine_tracks`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..skeleton import JOINTS, N_JOINTS
from ..tracks import Tracks
from .fuse import FuseSettings, JointFusion, TrackedRun, fuse_joint

#: What to do with a detector position that disagrees with the fused path: keep the detector's
#: (the track cleaning downstream judges it, as without refinement), take the fused path's, or
#: make it missing.
DISAGREE_POLICIES = ("detector", "refined", "missing")


@dataclass
class RefineReport:
    """Per joint: the detector's estimated noise (px), its share of frames that agreed, runs used and
    dropped; and the totals the operator reports."""

    joints: dict = field(default_factory=dict)
    frames: int = 0
    refined_entries: int = 0
    disagreeing_entries: int = 0
    filled_entries: int = 0
    runs_used: int = 0
    runs_dropped: int = 0

    def summary(self) -> str:
        noise = [j["detector_px"] for j in self.joints.values() if j["runs_used"]]
        if not noise:
            return "No tracked run agreed with the detector: the tracks are unchanged"
        text = (f"Refined {self.refined_entries} joint positions of {len(self.joints)} joints over {self.frames} "
                f"frames (detector noise ~{float(np.median(noise)):.1f} px)")
        if self.disagreeing_entries:
            text += f"; {self.disagreeing_entries} detector positions disagreed with the tracked motion"
        if self.filled_entries:
            text += f"; {self.filled_entries} missing positions filled from tracking"
        if self.runs_dropped:
            text += f"; {self.runs_dropped} of {self.runs_used + self.runs_dropped} tracked runs dropped"
        return text

    def to_dict(self) -> dict:
        return {"frames": self.frames, "refined_entries": self.refined_entries,
                "disagreeing_entries": self.disagreeing_entries, "filled_entries": self.filled_entries,
                "runs_used": self.runs_used, "runs_dropped": self.runs_dropped, "joints": self.joints}


def seed_plan(tracks: Tracks, window: int) -> list[tuple[int, dict[int, tuple[float, float]]]]:
    """Where to start the tracker: every ``window`` frames (the runs overlap by one frame so the
    tracked motion chains), each joint seen there seeded at the detector's position.
    Returns ``[(frame, {joint: (x, y)}), ...]`` with 0-based frames; frames with no joint are left out.
    """
    if window < 1:
        raise InputError(f"the tracking window must be at least 1 frame, got {window}")
    plan = []
    for start in range(0, max(tracks.n_frames - 1, 1), int(window)):
        seeds = {j: (float(tracks.xy[start, j, 0]), float(tracks.xy[start, j, 1]))
                 for j in range(N_JOINTS) if tracks.present[start, j]}
        if seeds:
            plan.append((start, seeds))
    return plan


#: A detector position this share of the figure's height away from where the joint's previous run
#: reached is taken for a miss, and the run goes on from its own position instead.
RESEED_SHARE = 0.025


def figure_height(tracks: Tracks) -> float:
    """The figure's median image height in the tracks' pixels (200 when no frame shows it)."""
    seen = np.isfinite(tracks.xy[..., 1]).any(axis=1)
    if not seen.any():
        return 200.0
    y = tracks.xy[seen, :, 1]
    return float(np.median(np.nanmax(y, axis=1) - np.nanmin(y, axis=1)))


def carried_seeds(tracks: Tracks, start: int, seeds: dict, runs: dict[int, list[TrackedRun]],
                  reseed_px: float) -> dict:
    """Where each joint's run from ``start`` begins: the detector's position (``seeds``, from
    :func:`seed_plan`), unless the joint's previous run reached this frame agreeing with the detector on
    its last two frames before it and the detector is missing here or further than ``reseed_px`` from
    that run's position (then the run's position, moved by its mean offset to the detector, so the
    runs do not drift from the detector)."""
    starts = dict(seeds)
    for j, joint_runs in runs.items():
        run = joint_runs[-1]
        k = start - run.start
        if not (1 <= k < len(run.xy)) or not np.isfinite(run.xy[k]).all() or k < 3:
            continue
        frames = run.start + np.arange(k + 1)
        diff = tracks.xy[frames, j] - run.xy[:k + 1]
        seen = np.isfinite(diff).all(axis=1)
        if seen.sum() < 3:
            continue
        offset = np.median(diff[seen], axis=0)
        recent = diff[k - 2:k]
        if not (np.isfinite(recent).all() and (np.linalg.norm(recent - offset, axis=1) <= reseed_px).all()):
            continue                       # the run may have slipped: the detector decides
        here = run.xy[k] + offset
        if j not in seeds or np.hypot(seeds[j][0] - here[0], seeds[j][1] - here[1]) > reseed_px:
            starts[j] = (float(here[0]), float(here[1]))
    return starts


def refine_tracks(tracks: Tracks, runs: dict[int, list[TrackedRun]], *,
                  settings: FuseSettings | None = None, disagree: str = "detector") -> tuple[Tracks, RefineReport]:
    """``tracks`` with every joint fused with its tracked ``runs`` (joint index -> runs).

    Entries where the detector and the fused path agree take the fused position; disagreeing ones
    follow ``disagree`` (:data:`DISAGREE_POLICIES`); frames the detector missed but the tracking
    links to its positions are filled with confidence 0.5. The static tracks are left alone.
    """
    if disagree not in DISAGREE_POLICIES:
        raise InputError(f"unknown policy for disagreeing positions '{disagree}' (one of {DISAGREE_POLICIES})")
    xy, conf = tracks.xy.copy(), tracks.conf.copy()
    report = RefineReport(frames=tracks.n_frames)
    for j in range(N_JOINTS):
        joint_runs = runs.get(j, [])
        if not joint_runs or not tracks.present[:, j].any():
            continue
        fused: JointFusion = fuse_joint(tracks.xy[:, j], joint_runs, settings)
        seen = tracks.present[:, j]
        ok = np.isfinite(fused.xy).all(axis=1)
        agree = fused.agree & ok
        against = seen & ok & ~fused.agree
        fill = ~seen & ok
        xy[agree, j] = fused.xy[agree]
        if disagree == "refined":
            xy[against, j] = fused.xy[against]
        elif disagree == "missing":
            xy[against, j] = np.nan
            conf[against, j] = 0.0
        xy[fill, j] = fused.xy[fill]
        conf[fill, j] = 0.5
        report.joints[JOINTS[j]] = {"detector_px": round(fused.detector_px, 3),
                                    "agree_share": round(float(agree.sum()) / max(int(seen.sum()), 1), 4),
                                    "runs_used": fused.runs_used, "runs_dropped": fused.runs_dropped}
        report.refined_entries += int(agree.sum())
        report.disagreeing_entries += int(against.sum())
        report.filled_entries += int(fill.sum())
        report.runs_used += fused.runs_used
        report.runs_dropped += fused.runs_dropped
    meta = dict(tracks.meta)
    meta["refined"] = report.to_dict()
    return tracks.replaced(xy=xy, conf=conf, meta=meta), report
