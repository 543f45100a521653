"""The tracking region's alignment points, steadied between frames as BlazePose does.

In tracking mode the next frame's region comes from the two alignment points
the landmark network returns.  Taken raw, a small or blurred person's region
can shrink a little every frame until the network no longer sees a person
(measured on real footage: docs/pose_detection.md).  MediaPipe's pose graph
always passes those two points through a One Euro filter (min cutoff 0.01 Hz,
beta 10, derivative cutoff 1 Hz, speeds measured in object sizes per second)
before it builds the region; this is that filter, written from the filter's
paper (Casiez, Roussel and Vogel 2012) and those published settings.

Only the region is steadied.  The landmarks written to the tracks stay the
network's raw answer in each frame (the estimator deals with detector errors).
"""

from __future__ import annotations

import math

import numpy as np

MIN_CUTOFF_HZ = 0.01
BETA = 10.0
DERIVATIVE_CUTOFF_HZ = 1.0


def _alpha(cutoff_hz, dt: float):
    """The low-pass weight of a new sample for a cutoff (Hz, scalar or array) at step ``dt`` seconds."""
    tau = 1.0 / (2.0 * math.pi * cutoff_hz)
    return 1.0 / (1.0 + tau / dt)


class AlignmentFilter:
    """One Euro filter over the two alignment points (2, 2) px; :meth:`reset` when the person is lost."""

    def __init__(self, fps: float):
        self.dt = 1.0 / float(fps)
        self.reset()

    def reset(self) -> None:
        self.value: np.ndarray | None = None   # filtered points
        self.raw: np.ndarray | None = None     # last raw points
        self.speed: np.ndarray | None = None   # filtered speed, object sizes per second

    def __call__(self, points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, dtype=float)
        if self.value is None:
            self.value, self.raw, self.speed = points.copy(), points.copy(), np.zeros_like(points)
            return points.copy()
        extent = points.max(axis=0) - points.min(axis=0)
        size = 0.5 * float(extent[0] + extent[1])
        if size <= 1e-6:  # no scale to measure speed against: pass the points through, as the reference does
            self.raw = points.copy()
            return points.copy()
        speed = (points - self.raw) / size / self.dt
        self.speed = self.speed + _alpha(DERIVATIVE_CUTOFF_HZ, self.dt) * (speed - self.speed)
        cutoff = MIN_CUTOFF_HZ + BETA * np.abs(self.speed)
        self.value = self.value + _alpha(cutoff, self.dt) * (points - self.value)
        self.raw = points.copy()
        return self.value.copy()
