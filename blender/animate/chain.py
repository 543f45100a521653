"""The footage-to-animation chain, a piece at a time: detect the pose, follow the background, estimate.

:class:`AnimateRun` holds one run. Each :meth:`AnimateRun.step` does one piece (a chunk of frames for the
detector, one look for Blender's tracker, a look at the estimate's thread) so a modal operator shows one
progress bar over all of it and takes Esc between pieces; :func:`run_to_end` runs it whole (scripts,
background Blender). Nothing is put into the scene while it runs: the detected tracks and the estimate
stay in memory and the background features carry temporary names on the clip, so a cancel or a failure
(:meth:`AnimateRun.abort`) leaves the scene as it was. The caller puts a finished run into the scene.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import bpy

from ...core.errors import Cancelled, InputError
from ..background_tracking.follow import BackgroundRun
from ..pose_detection.clip_detect import ClipDetection, rotation_warning
from ..worker import FALLBACK_META, with_background_warning

#: Share of the progress bar each stage takes: a rough split of a run's time (on the tests' 16-frame clip the
#: detector took 1.1 s and the background 5.8 s; on long clips the detector's share grows).
WEIGHTS = {"detect": 0.45, "background": 0.3, "estimate": 0.25}
#: Longest wait, on abort, for the estimate's thread to see the cancel (it checks every iteration).
ABORT_WAIT_S = 60.0
STAGE_NAMES = {"detect": "Detecting the pose", "background": "Following the background",
               "estimate": "Estimating", "ready": "Building"}


@dataclass
class AnimateOptions:
    """What the run does (the sidebar's settings)."""

    mode: str = "tracking"          # the detector's mode (core.pose_detection.tracker.MODES)
    step: int = 1                   # detect on every n-th frame (the background then is not followed)
    background: bool = True         # follow the background for the camera
    method: str | None = None       # estimator (None: the default)
    focal_mm: float | None = None   # a known lens (36 mm film), else estimated
    height_m: float = 1.75
    fps: float | None = None        # when the clip has none (image sequences)


@dataclass
class StageNote:
    """What a stage found, for the report and the sidebar's summary."""

    stage: str
    level: str                      # 'INFO' or 'WARNING'
    text: str


@dataclass
class AnimateRun:
    """One run over a Movie Clip; :meth:`step` until :attr:`ready`, then the caller commits it."""

    clip_name: str
    options: AnimateOptions
    detection: ClipDetection
    stage: str = "detect"
    notes: list = field(default_factory=list)
    background: BackgroundRun | None = None
    job: object = None
    detected: object = None         # core.pose_detection Detection
    tracks: object = None           # the tracks the estimate used (background features as static tracks)
    static_kept: bool = False       # the background features are used (and wait on the clip to be adopted)
    estimate: object = None
    cancel_requested: bool = False
    seconds: dict = field(default_factory=dict)
    _started: float = 0.0

    @classmethod
    def start(cls, clip, options: AnimateOptions, *, networks=None, chunk: int = 24) -> AnimateRun:
        detection = ClipDetection(clip, step=options.step, mode=options.mode, networks=networks, chunk=chunk,
                                  fps=options.fps)
        return cls(clip.name, options, detection, _started=time.perf_counter())

    # ------------------------------------------------------------------ progress
    @property
    def ready(self) -> bool:
        return self.stage == "ready"

    @property
    def waiting(self) -> bool:
        """Whether the run is waiting on the estimate's thread (a caller without a timer may sleep)."""
        return self.stage == "estimate"

    def _stage_fraction(self) -> float:
        if self.stage == "detect":
            return self.detection.fraction
        if self.stage == "background" and self.background is not None:
            return self.background.fraction
        if self.stage == "estimate" and self.job is not None:
            return self.job.snapshot().fraction
        return 1.0

    @property
    def fraction(self) -> float:
        done, total = 0.0, 0.0
        order = ("detect", "background", "estimate")
        for name in order:
            total += WEIGHTS[name]
            if self.stage == "ready" or order.index(name) < order.index(self.stage):
                done += WEIGHTS[name]
            elif name == self.stage:
                done += WEIGHTS[name] * self._stage_fraction()
        return min(1.0, done / total)

    @property
    def message(self) -> str:
        name = STAGE_NAMES.get(self.stage, self.stage)
        if self.stage == "detect":
            return f"{name}: {len(self.detection.run.numbers)}/{self.detection.frames.total} frames"
        if self.stage == "background" and self.background is not None:
            return f"{name}: look {self.background.next_look}/{len(self.background.looks)}"
        if self.stage == "estimate" and self.job is not None:
            state = self.job.snapshot()
            return f"{name}: {state.message}" if state.message else name
        return name

    def cancel(self) -> None:
        """Stop at the end of the current piece (the estimate's thread at its next check)."""
        self.cancel_requested = True
        if self.job is not None:
            self.job.cancel()

    # ------------------------------------------------------------------ stepping
    def _clip(self):
        clip = bpy.data.movieclips.get(self.clip_name)
        if clip is None:
            raise InputError(f"clip '{self.clip_name}' was removed during Animate from Clip")
        return clip

    def _note(self, stage: str, level: str, text: str) -> None:
        self.notes.append(StageNote(stage, level, text))

    def _timed(self, stage: str) -> None:
        now = time.perf_counter()
        self.seconds[stage] = now - self._started
        self._started = now

    def step(self, context) -> None:
        """Do the next piece of work; raises :class:`core.errors.Cancelled` once a cancel was asked for."""
        if self.cancel_requested:
            raise Cancelled("Animate from Clip cancelled")
        if self.stage == "detect":
            self.detection.step()
            if self.detection.done:
                self._detected(context)
        elif self.stage == "background":
            self.background.step(context)
            if self.background.done:
                self._followed(context)
        elif self.stage == "estimate":
            state = self.job.snapshot()
            if not state.done:
                return
            if state.cancelled:
                raise Cancelled("Animate from Clip cancelled")
            if state.error is not None:
                raise state.error
            self.estimate = with_background_warning(state.result, self.tracks)
            self._timed("estimate")
            est = self.estimate
            self._note("estimate", "INFO", f"estimate: {est.method}, focal {est.focal_mm:.1f} mm, "
                                           f"{len(est.frames)} frames, {len(est.diagnostics.get('warnings', []))} "
                                           "warning(s)")
            self.stage = "ready"

    def _detected(self, context) -> None:
        self.detection.frames.close()
        result = self.detection.run.finish()       # no person anywhere: one line, nothing written
        self.detected = result
        self._timed("detect")
        clip = self._clip()
        for note in result.notes + [w for w in [rotation_warning(clip)] if w]:
            self._note("detect", "WARNING", note)
        n = len(result.frame_numbers)
        self._note("detect", "INFO", f"pose: person in {100 * result.found_share:.0f} % of {n} frames "
                                     f"({self.seconds['detect']:.1f} s)")
        self.tracks = result.tracks
        if not self.options.background:
            self._note("background", "INFO", "background: not followed (switched off): the camera comes from "
                                             "the person alone")
        elif self.options.step != 1:
            self._note("background", "WARNING", f"background: not followed, the pose was detected on one frame "
                                                 f"in {self.options.step}: the camera comes from the person alone")
        else:
            self.background = BackgroundRun(clip, self.tracks, first_clip_frame=result.frame_numbers[0])
            self.stage = "background"
            return
        self._start_estimate()

    def _followed(self, context) -> None:
        static, report = self.background.finish(context)
        self._timed("background")
        took = f" ({self.seconds['background']:.1f} s)"
        if static is None:
            self.background.discard(context)
            self._note("background", "WARNING", report.fallback + took)
            self.tracks = self.tracks.replaced(meta={**self.tracks.meta, FALLBACK_META: report.fallback})
        else:
            self.static_kept = True
            self._note("background", "WARNING" if report.frames_under_four else "INFO",
                       f"background: {report.summary()}{took}")
            self.tracks = self.tracks.replaced(static=static)
        self._start_estimate()

    def _start_estimate(self) -> None:
        from ...core.estimate import DEFAULT_METHOD, estimate
        from ..estimate_job import EstimateJob  # plain Python: a thread with progress and cancel

        tracks, opts = self.tracks, self.options

        def run(progress=None, should_cancel=None):
            return estimate(tracks, opts.method or DEFAULT_METHOD, focal_mm=opts.focal_mm, height_m=opts.height_m,
                            progress=progress, should_cancel=should_cancel, background=opts.background)

        self.job = EstimateJob(run).start()
        self.stage = "estimate"

    def abort(self, context) -> None:
        """Stop and leave no trace: close the decoder, remove the run's features from the clip, stop the thread."""
        self.detection.abort()
        if self.job is not None:
            self.job.cancel()
            # the thread stops at its next check; waited for, so no later run's decoding overlaps its numpy
            # work (measured: a Blender render on the main thread beside a live estimate thread can crash)
            self.job.wait(ABORT_WAIT_S)
        if self.background is not None:
            self.background.discard(context)


def run_to_end(run: AnimateRun, context, progress=None) -> AnimateRun:
    """Step ``run`` until it is ready (``progress(fraction)`` after each piece); abort it on any failure."""
    try:
        while not run.ready:
            run.step(context)
            if run.waiting:
                run.job.wait(0.05)
            if progress is not None:
                progress(run.fraction)
    except BaseException:
        run.abort(context)
        raise
    return run
