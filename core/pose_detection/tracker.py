"""One person through a clip: detect, read landmarks, follow the region from frame to frame.

Two modes, as the issue asks:

* ``tracking`` (default): the detector runs only when no person is being
  followed; otherwise the previous frame's alignment landmarks give this
  frame's region.  When the pose score falls under 0.5 the person is taken as
  lost and the detector runs again on the same frame.
* ``per-frame``: the detector runs on every frame (slower, never carries a
  wrong region forward).

Nothing is smoothed: the landmarks are the network's raw answer in each frame
(robustness to a detector's errors is the estimator's job).

One person: when the detector runs while a person was followed less than
:data:`MEMORY_S` ago (per-frame mode, or after a loss), it takes the detection
nearest to where that person was (within :data:`NEAR_SIDES` region sides),
not the highest-scoring one, so someone else in the shot (an embrace, a
passer-by) does not take over the tracks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import blazepose
from .roi import Region

MODES = ("tracking", "per-frame")
#: How long (seconds) the last answer's place is remembered, and how near (region sides) a detection must be.
MEMORY_S = 1.0
NEAR_SIDES = 0.5


@dataclass
class FramePose:
    """A frame's answer: (33, 2) px landmarks, (33,) visibility; NaN / 0 when no person was found."""

    xy: np.ndarray
    visibility: np.ndarray


class PoseTracker:
    """Feeds frames (H, W, 3 RGB arrays) one at a time to BlazePose; holds the region between frames."""

    def __init__(self, networks, mode: str = "tracking", fps: float = 30.0):
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, not {mode!r}")
        self.networks = networks
        self.mode = mode
        self.region: Region | None = None
        self.detector_runs = 0
        self.memory_frames = max(1, round(MEMORY_S * fps))
        self.last: Region | None = None      # where the person was last answered
        self.since_last = 0                  # frames since then

    def _detect(self, image: np.ndarray) -> Region | None:
        self.detector_runs += 1
        tensor, frame = blazepose.detector_input(image)
        found = blazepose.decode_detections(*self.networks.detect(tensor), frame)
        if not found:
            return None
        regions = [d.region() for d in found]
        if self.last is not None and self.since_last <= self.memory_frames and len(regions) > 1:
            gaps = [np.hypot(r.center[0] - self.last.center[0], r.center[1] - self.last.center[1]) for r in regions]
            nearest = int(np.argmin(gaps))
            if gaps[nearest] <= NEAR_SIDES * self.last.side:
                return regions[nearest]
        return regions[0]

    def _landmarks(self, image: np.ndarray, region: Region) -> blazepose.Landmarks:
        raw, flag, heatmap = self.networks.landmark(blazepose.landmark_input(image, region))
        return blazepose.decode_landmarks(raw, flag, heatmap, region)

    def process(self, image: np.ndarray) -> FramePose:
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] < 3:
            raise ValueError(f"a frame must be H x W x 3 (RGB), got {image.shape}")
        image = image[..., :3]
        region = self.region if self.mode == "tracking" else None
        answer = None
        if region is not None:
            answer = self._landmarks(image, region)
            if answer.score < blazepose.MIN_PRESENCE:
                answer = None
        if answer is None:
            region = self._detect(image)
            if region is not None:
                answer = self._landmarks(image, region)
                if answer.score < blazepose.MIN_PRESENCE:
                    answer = None
        self.since_last += 1
        if answer is None:
            self.region = None
            return FramePose(np.full((blazepose.N_LANDMARKS, 2), np.nan), np.zeros(blazepose.N_LANDMARKS))
        self.region = answer.next_region
        self.last, self.since_last = answer.next_region, 0
        return FramePose(answer.xy, answer.visibility)
