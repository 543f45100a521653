"""Step 2 (paper 3.2): split the clip into still-camera and moving-camera spells.

A planted foot does not move in the world, so while the camera is still its image
does not move either.  The paper's assumptions (camera still >= 1 s between
motions, stance foot still >= 1 s) guarantee that at least p/2 frames of every
still spell show one foot practically motionless.  So: accumulate each foot's
image movement over every window of p/2 frames; wherever one foot's total stays
below a threshold, all frames of that window were filmed by a still camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..runs import runs as _runs
from .params import PaperParams


@dataclass
class Spell:
    start: int        # first frame
    end: int          # last frame (inclusive, as in the truth JSON)
    moving: bool
    kind: str = "still"

    def as_dict(self) -> dict:
        return {"start": int(self.start), "end": int(self.end), "kind": self.kind}


def foot_steps(feet: np.ndarray) -> np.ndarray:
    """Per-frame image movement (F, 2) of the two feet; frame 0 and unknown steps are inf."""
    step = np.linalg.norm(np.diff(feet, axis=0), axis=-1)
    step = np.where(np.isfinite(step), step, np.inf)
    return np.vstack([np.full((1, feet.shape[1]), np.inf), step])


def still_frames(feet: np.ndarray, fps: float, threshold_per_frame: float, params: PaperParams) -> np.ndarray:
    """(F,) bool: frame lies in a p/2-frame window where one foot's accumulated movement is small.

    ``feet`` is (F, 2, 2) image positions of the left and right ankle; the
    threshold is in the same units per frame of the window.
    """
    n = feet.shape[0]
    w = min(n, params.window_frames(params.still_window_s, fps, minimum=2))
    steps = foot_steps(feet)
    still = np.zeros(n, dtype=bool)
    if n < 2:
        return still
    # Accumulated movement inside window [a, a + w): the steps a+1 .. a+w-1.
    finite = np.where(np.isfinite(steps), steps, 1e12)
    csum = np.vstack([np.zeros((1, 2)), np.cumsum(finite, axis=0)])
    starts = np.arange(0, n - w + 1)
    acc = csum[starts + w] - csum[starts + 1]               # (n-w+1, 2)
    ok = acc.min(axis=1) < threshold_per_frame * (w - 1)
    cover = np.zeros(n + 1, dtype=int)
    np.add.at(cover, starts[ok], 1)
    np.add.at(cover, starts[ok] + w, -1)
    still = np.cumsum(cover)[:n] > 0
    return still


def segment(feet: np.ndarray, fps: float, threshold_per_frame: float, params: PaperParams) -> list[Spell]:
    """Still and moving spells covering every frame, in order."""
    n = feet.shape[0]
    still = still_frames(feet, fps, threshold_per_frame, params)
    min_motion = params.window_frames(params.min_motion_s, fps)
    moving = ~still
    for a, b in _runs(moving):
        if b - a < min_motion:
            moving[a:b] = False
    grow = params.window_frames(params.motion_extend_s, fps, minimum=0)
    if grow:
        # A p/2 window reaching into the slow start or end of a motion still passes as still, so
        # every detected motion starts late and ends early by a few frames: give them back.
        for a, b in _runs(moving.copy()):
            moving[max(0, a - grow):min(n, b + grow)] = True
    spells = []
    a = 0
    while a < n:
        b = a
        while b + 1 < n and moving[b + 1] == moving[a]:
            b += 1
        spells.append(Spell(a, b, bool(moving[a]), "moving" if moving[a] else "still"))
        a = b + 1
    return spells
