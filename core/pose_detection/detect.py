"""From frames to ``skeleton-tracks``: BlazePose on every frame, its 33 landmarks mapped to 17 joints.

:func:`detect_frames` is the API the command line and Blender share.  It
takes any iterable of RGB frames, reports progress per frame, and stops when
``should_cancel()`` says so, keeping what it found (``cancelled`` is then set
on the result).  The joints are the network's raw answer with its visibility
as the confidence: no smoothing or clean-up (the estimator's cleaning is
built for a detector's errors and must see them).  The network's metric 3D
joints ride along as :attr:`core.tracks.Tracks.landmarks_3d`
(:mod:`.world_joints`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..io.formats.mediapipe import landmarks_to_tracks
from ..track_cleaning.people import person_switches
from ..tracks import Tracks
from .tracker import MODES, PoseTracker
from .world_joints import world_joints

#: the fps assumed when neither the source nor the caller gives one
DEFAULT_FPS = 30.0


@dataclass
class Detection:
    """What :func:`detect_frames` found: the tracks and the raw landmarks behind them."""

    tracks: Tracks | None
    landmarks: np.ndarray        # (F, 33, 2) px, NaN where no person
    visibility: np.ndarray       # (F, 33)
    frame_numbers: list[int]     # source frame index of each row
    detector_runs: int
    seconds: float
    cancelled: bool = False
    notes: list[str] = field(default_factory=list)
    world: np.ndarray | None = None   # (F, 33, 3) m, the network's world landmarks (NaN where no person)

    @property
    def found_share(self) -> float:
        """Share of frames with a person."""
        if not len(self.frame_numbers):
            return 0.0
        return float(np.isfinite(self.landmarks[:, 0, 0]).mean())


class DetectionRun:
    """Frames fed one at a time (:meth:`add`), the tracks at the end (:meth:`finish`).

    For callers that cannot hand over an iterator, such as a Blender modal
    operator that decodes a few frames on each timer tick.
    """

    def __init__(self, *, fps: float | None, image_size: tuple[int, int] | None = None, networks=None,
                 mode: str = "tracking", step: int = 1, source: str = "", lens=None):
        if mode not in MODES:
            raise InputError(f"detection mode must be one of {', '.join(MODES)}, not {mode!r}")
        if step < 1:
            raise InputError(f"step must be 1 or more, got {step}")
        if networks is None:
            from .runtime import Networks
            networks = Networks()
        self.fps = float(fps) if fps else DEFAULT_FPS
        self.tracker = PoseTracker(networks, mode, fps=self.fps / step)
        self.size = tuple(int(v) for v in image_size) if image_size else None
        self.mode, self.step, self.source = mode, step, source
        self.lens = lens          # a core.lens.prior.Lens the footage recorded, kept in the tracks' meta
        self.xy, self.vis, self.world, self.numbers = [], [], [], []
        self.seconds = 0.0

    def add(self, frame: np.ndarray, number: int) -> None:
        """Detect in ``frame``, source frame ``number``."""
        start = time.perf_counter()
        frame = np.asarray(frame)
        if self.size is None:
            self.size = (frame.shape[1], frame.shape[0])
        elif (frame.shape[1], frame.shape[0]) != self.size:
            where = f"{self.source}: " if self.source else ""
            raise InputError(f"{where}frame {number} is {frame.shape[1]}x{frame.shape[0]}, "
                             f"the clip {self.size[0]}x{self.size[1]}")
        pose = self.tracker.process(frame)
        self.xy.append(pose.xy)
        self.vis.append(pose.visibility)
        self.world.append(pose.world)
        self.numbers.append(int(number))
        self.seconds += time.perf_counter() - start

    def finish(self, cancelled: bool = False) -> Detection:
        """The result; an :class:`InputError` when nothing was found (unless ``cancelled``)."""
        landmarks = np.array(self.xy).reshape(-1, 33, 2)
        visibility = np.array(self.vis).reshape(-1, 33)
        world = np.array(self.world, dtype=float).reshape(-1, 33, 3)
        result = Detection(None, landmarks, visibility, list(self.numbers), self.tracker.detector_runs,
                           self.seconds, cancelled, world=world)
        where = f"{self.source}: " if self.source else ""
        if not self.numbers:
            if cancelled:
                return result
            raise InputError(f"{where}no frames to detect in")
        found = np.isfinite(landmarks[:, 0, 0])
        if not found.any():
            if cancelled:
                return result
            raise InputError(f"{where}no person found in any of the {len(self.numbers)} frames")
        if not found.all():
            lost = np.flatnonzero(~found)
            result.notes.append(f"no person in {lost.size} of {len(self.numbers)} frames (first at frame "
                                f"{self.numbers[lost[0]]}); those frames are missing in the tracks")
        norm = landmarks / np.array(self.size, dtype=float)
        meta = {"detector": "BlazePose full (MediaPipe pose_landmark_full), offline", "mode": self.mode,
                "step": self.step, "first_frame": self.numbers[0], "frames_with_person": int(found.sum())}
        if self.lens is not None:
            meta.update(self.lens.meta())
        if cancelled:
            meta["cancelled_after"] = len(self.numbers)
        tracks = landmarks_to_tracks(norm, visibility, fps=self.fps / self.step, image_size=self.size,
                                     source=self.source or "detect", meta=meta)
        joints_3d = world_joints(world)
        result.tracks = tracks.replaced(landmarks_3d=joints_3d) if np.isfinite(joints_3d).any() else tracks
        switches = person_switches(result.tracks.xy)
        if switches.size:
            listed = ", ".join(str(self.numbers[i]) for i in switches[:5]) + (" ..." if switches.size > 5 else "")
            result.notes.append(f"the tracks may jump to another person at frame {listed} (people crossing, or "
                                "someone else found after a loss): estimate one person's stretch, or correct them")
        return result


def detect_frames(frames: Iterable[np.ndarray], *, fps: float | None, image_size: tuple[int, int] | None = None,
                  networks=None, mode: str = "tracking", step: int = 1, first_frame: int = 0,
                  total: int | None = None, source: str = "", progress: Callable[[int, int | None], None] | None = None,
                  should_cancel: Callable[[], bool] | None = None, lens=None) -> Detection:
    """Detect one person in ``frames`` (every ``step``-th is used; the first is source frame ``first_frame``).

    ``networks`` defaults to the bundled BlazePose (:class:`.runtime.Networks`).
    ``total`` is the number of frames that will be used, for progress only.
    The tracks' frame rate is ``fps / step``.  No frame at all, or no person
    in any frame, is an :class:`InputError` unless cancelled.  ``lens`` (a :class:`core.lens.prior.Lens`
    the footage recorded) is kept in the tracks' meta for the estimate.
    """
    run = DetectionRun(fps=fps, image_size=image_size, networks=networks, mode=mode, step=step, source=source,
                       lens=lens)
    for i, frame in enumerate(frames):
        if i % step:
            continue
        if should_cancel is not None and should_cancel():
            return run.finish(cancelled=True)
        run.add(frame, first_frame + i)
        if progress is not None:
            progress(len(run.numbers), total)
    return run.finish()
