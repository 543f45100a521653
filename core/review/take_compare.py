"""Two takes of one clip side by side: how their bones and their joints differ.

A take is one build of an estimate (a method, settings, a time).  Comparing two tells an animator
whether a change of method or setting moved the answer: per bone class, the two lengths as built;
per frame both takes posed, the mean distance between their joints in the scene, and which joints
and frames differ most.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..skeleton import CLASSES, JOINTS


@dataclass
class TakeComparison:
    """Lengths in metres, distances in millimetres; frames are estimate frame indices."""

    lengths_a: np.ndarray          # (10,) bone class lengths of take A
    lengths_b: np.ndarray          # (10,)
    frames: np.ndarray             # (n,) frames both takes posed
    frame_mm: np.ndarray           # (n,) mean joint distance per common frame
    joint_mm: np.ndarray           # (17,) mean distance per joint over the common frames

    @property
    def length_diff_mm(self) -> np.ndarray:
        return 1000.0 * (self.lengths_b - self.lengths_a)

    @property
    def mean_mm(self) -> float:
        return float(np.mean(self.frame_mm)) if self.frame_mm.size else float("nan")

    @property
    def max_mm(self) -> float:
        return float(np.max(self.frame_mm)) if self.frame_mm.size else float("nan")

    def worst_frames(self, n: int = 3) -> list[tuple[int, float]]:
        """(frame, mean mm) of the ``n`` frames where the takes differ most, largest first."""
        order = np.argsort(-self.frame_mm, kind="stable")[:n]
        return [(int(self.frames[i]), float(self.frame_mm[i])) for i in order]

    def worst_joints(self, n: int = 3) -> list[tuple[str, float]]:
        ok = np.isfinite(self.joint_mm)
        order = [int(j) for j in np.argsort(-np.where(ok, self.joint_mm, -1.0), kind="stable") if ok[j]][:n]
        return [(JOINTS[j], float(self.joint_mm[j])) for j in order]

    def to_dict(self) -> dict:
        return {
            "lengths_a_m": [float(v) for v in self.lengths_a], "lengths_b_m": [float(v) for v in self.lengths_b],
            "frames": [int(f) for f in self.frames], "frame_mm": [float(v) for v in self.frame_mm],
            "joint_mm": [None if not np.isfinite(v) else float(v) for v in self.joint_mm],
        }

    @classmethod
    def from_dict(cls, doc: dict) -> TakeComparison:
        return cls(np.array(doc["lengths_a_m"], dtype=float), np.array(doc["lengths_b_m"], dtype=float),
                   np.array(doc["frames"], dtype=int), np.array(doc["frame_mm"], dtype=float),
                   np.array([np.nan if v is None else v for v in doc["joint_mm"]], dtype=float))

    def summary(self) -> dict:
        """What a panel shows, small and ready to draw (no per-frame arrays): frame count, mean and
        largest distance, the three worst joints and frames, the bone table."""
        if not self.frames.size:
            return {"frames": 0}
        return {"frames": int(self.frames.size), "mean_mm": self.mean_mm, "max_mm": self.max_mm,
                "worst_joints": self.worst_joints(3), "worst_frames": self.worst_frames(3),
                "rows": self.summary_rows()}

    def summary_rows(self) -> list[list[str]]:
        """The bone table: class, A, B, B - A (centimetres)."""
        rows = [["Bone", "A cm", "B cm", "B-A"]]
        for i, name in enumerate(CLASSES):
            rows.append([name, f"{100 * self.lengths_a[i]:.1f}", f"{100 * self.lengths_b[i]:.1f}",
                         f"{self.length_diff_mm[i] / 10:+.1f}"])
        return rows


def compare_takes(lengths_a, frames_a, joints_a, lengths_b, frames_b, joints_b) -> TakeComparison:
    """Compare take B with take A, each given as class lengths (10,) metres, the frames it posed (n,)
    and their finite world joints (n, 17, 3) metres."""
    la, lb = (np.asarray(v, dtype=float).reshape(len(CLASSES)) for v in (lengths_a, lengths_b))
    fa, fb = np.asarray(frames_a, dtype=int), np.asarray(frames_b, dtype=int)
    ja, jb = np.asarray(joints_a, dtype=float), np.asarray(joints_b, dtype=float)
    common, ia, ib = np.intersect1d(fa, fb, return_indices=True)
    if common.size == 0:
        return TakeComparison(la, lb, common, np.zeros(0), np.full(len(JOINTS), np.nan))
    dist = 1000.0 * np.linalg.norm(ja[ia] - jb[ib], axis=-1)            # (n, 17) mm
    return TakeComparison(la, lb, common, np.mean(dist, axis=1), np.mean(dist, axis=0))
