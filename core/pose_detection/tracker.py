"""One person through a clip: detect, read landmarks, follow the region from frame to frame.

Two modes:

* ``tracking`` (default): the detector runs only when no person is being
  followed; otherwise the previous frame's alignment landmarks give this
  frame's region (steadied as BlazePose does: :mod:`.region_filter`).  When
  the pose score falls under 0.5, a wider region is tried once; if it fails
  too, the person is taken as lost and the detector runs again on the same
  frame (on tiles of it when the whole frame shows nobody).
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
from .region_filter import AlignmentFilter
from .roi import Region, region_from_alignment

MODES = ("tracking", "per-frame")
#: How long (seconds) the last answer's place is remembered, and how near (region sides) a detection must be.
MEMORY_S = 1.0
NEAR_SIDES = 0.5
#: a followed region whose pose score fails is looked at once more this much wider before the detector runs
RETRY_WIDER = 1.25


@dataclass
class FramePose:
    """A frame's answer: (33, 2) px landmarks, (33,) visibility, (33, 3) world landmarks in metres
    (:class:`.blazepose.Landmarks`); NaN / 0 when no person was found (world NaN too when the networks
    give none)."""

    xy: np.ndarray
    visibility: np.ndarray
    world: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.world is None:
            self.world = np.full((blazepose.N_LANDMARKS, 3), np.nan)


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
        self.steady = AlignmentFilter(fps)

    def _detect(self, image: np.ndarray) -> Region | None:
        found, runs = blazepose.find_people(image, self.networks.detect)
        self.detector_runs += runs
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
        out = self.networks.landmark(blazepose.landmark_input(image, region))
        raw, flag, heatmap = out[:3]
        world = out[3] if len(out) > 3 else None      # a stand-in network may give no world landmarks
        return blazepose.decode_landmarks(raw, flag, heatmap, region, world)

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
                # the score of a region that fits is unsteady: one wider look before calling the person lost
                answer = self._landmarks(image, Region(region.center, region.side * RETRY_WIDER, region.rotation))
                if answer.score < blazepose.MIN_PRESENCE:
                    answer = None
        if answer is None:
            self.steady.reset()
            region = self._detect(image)
            if region is not None:
                answer = self._landmarks(image, region)
                if answer.score < blazepose.MIN_PRESENCE:
                    answer = None
        self.since_last += 1
        if answer is None:
            self.region = None
            return FramePose(np.full((blazepose.N_LANDMARKS, 2), np.nan), np.zeros(blazepose.N_LANDMARKS))
        self.region = region_from_alignment(*self.steady(answer.alignment))
        self.last, self.since_last = self.region, 0
        return FramePose(answer.xy, answer.visibility, answer.world)
