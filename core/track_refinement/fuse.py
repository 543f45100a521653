"""One joint's image path from a detector's positions and a tracker's short tracked runs.

A 2D detector finds each joint anew in every frame: right on average, but with a few pixels of jitter
and now and then a gross miss. An image tracker (least-squares matching, as Blender's libmv tracker
does) follows a patch from frame to frame to a fraction of a pixel, but only for a while: it knows
nothing of joints, starts wherever it is seeded and slips when the patch changes. So the tracker is
trusted for the *motion between frames* and the detector for *where the joint is*: the path ``x`` is
the least-squares compromise of

* ``x(t) = d(t)``, detector positions, each with the detector's noise (estimated from the clip) and a
  Huber loss so a detector's miss is outvoted by the tracked motion around it, and
* ``x(t+1) - x(t) = p(t+1) - p(t)``, the tracker's steps, each with ``tracker_px`` of noise.

Both axes are independent, and the normal equations are tridiagonal (one banded solve per axis).
A tracked run that disagrees with the detector over most of its frames (the tracker was seeded on a
detector's miss or slipped off the joint) is left out before the solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

from ..joint_solve.solver import huber
from ..nanstats import RAYLEIGH_MEDIAN


@dataclass(frozen=True)
class FuseSettings:
    """How much each source is believed.

    ``tracker_px``: noise of one tracked frame-to-frame step (libmv reaches about 0.1 px on sharp
    texture; 0.3 leaves room for blur). ``detector_px``: the detector's noise when it cannot be
    estimated (fewer than ``min_frames_for_noise`` frames with both sources), else only its floor.
    A detector position more than ``agree_sigmas`` noise levels from the fused path disagrees; a
    run with more than ``run_disagree_share`` of its frames disagreeing is dropped.
    """

    tracker_px: float = 0.3
    detector_px: float = 2.0
    min_detector_px: float = 0.3
    agree_sigmas: float = 4.0
    run_disagree_share: float = 0.5
    min_frames_for_noise: int = 10
    step_huber: float = 3.0
    iterations: int = 4


@dataclass
class TrackedRun:
    """One tracker run: ``xy`` (k, 2) pixels on frames ``start .. start + k - 1``, NaN where lost."""

    start: int
    xy: np.ndarray

    def frames(self) -> np.ndarray:
        return self.start + np.arange(len(self.xy))


@dataclass
class JointFusion:
    """What fusing one joint found: the path, where the detector agreed, and the counts."""

    xy: np.ndarray
    agree: np.ndarray
    detector_px: float
    runs_used: int = 0
    runs_dropped: int = 0


def _run_steps(runs: list[TrackedRun], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Frame-to-frame steps of the kept runs: (m,) frame t of each step ``t -> t+1`` and (m, 2) steps.
    Where two runs give the same step, both are kept (two measurements)."""
    frames, steps = [], []
    for run in runs:
        f = run.frames()
        d = np.diff(run.xy, axis=0)
        ok = np.isfinite(d).all(axis=1) & (f[1:] < n) & (f[:-1] >= 0)
        frames.append(f[:-1][ok])
        steps.append(d[ok])
    if not frames:
        return np.zeros(0, dtype=int), np.zeros((0, 2))
    return np.concatenate(frames), np.concatenate(steps)


def _run_offset(diff: np.ndarray, threshold: float) -> np.ndarray:
    """The constant offset from a run to the detector that most of its frames agree with (within
    ``threshold``), refined as their mean; among equals the smallest, as the run starts at its seed
    (a run half covering a three-frame miss has two equal candidates, and the miss is not its seed)."""
    candidates = np.vstack([np.zeros(2), diff])
    counts = (np.linalg.norm(diff[None, :, :] - candidates[:, None, :], axis=2) <= threshold).sum(axis=1)
    best = np.flatnonzero(counts == counts.max())
    pick = candidates[best[np.argmin(np.linalg.norm(candidates[best], axis=1))]]
    inliers = np.linalg.norm(diff - pick, axis=1) <= threshold
    return diff[inliers].mean(axis=0) if inliers.any() else pick


def _paired(run: TrackedRun, detector: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The run's positions and the detector's on the run's frames ((k, 2) each, NaN outside the clip),
    and where both are there."""
    f = run.frames()
    inside = (f >= 0) & (f < len(detector))
    xy = np.where(inside[:, None], run.xy, np.nan)
    d = np.full_like(xy, np.nan)
    d[inside] = detector[f[inside]]
    return xy, d, np.isfinite(xy).all(axis=1) & np.isfinite(d).all(axis=1)


def _judge_run(run: TrackedRun, detector: np.ndarray, threshold: float, share: float) -> TrackedRun | None:
    """The part of ``run`` the detector vouches for, or None.

    At the run's best constant offset, frames more than ``threshold`` from the detector are far. A
    run with over ``share`` of its frames far is dropped (seeded on a detector's miss, or lost); a run
    whose last frames are far (two or more, never agreeing again) is cut where they start: the tracker
    slipped onto something else, a crossing limb. Far frames followed by agreement are the detector's
    misses and are kept.
    """
    xy, d, both = _paired(run, detector)
    if both.sum() < 3:
        return run                       # too short to judge: its steps face the Huber loss alone
    offset = _run_offset(d[both] - xy[both], threshold)
    far = both & (np.linalg.norm(d - xy - offset, axis=1) > threshold)
    if far.sum() > share * both.sum():
        return None
    # a slip lasts: the tracker stays on whatever it slipped onto until the run ends, while a
    # detector's miss of a few frames is followed by agreement again
    last = np.flatnonzero(both & ~far)
    tail = far[last[-1] + 1:] if last.size else far
    if tail.sum() >= 2:
        cut = int(last[-1]) + 1 if last.size else 0
        first_far = cut + int(np.flatnonzero(tail)[0])
        if first_far < 2:
            return None
        return TrackedRun(run.start, xy[:first_far].copy())
    return run


def _detector_noise(runs: list[TrackedRun], detector: np.ndarray, settings: FuseSettings) -> float:
    """The detector's noise per axis (px): its scatter about the tracked runs, each at its best offset
    (a run's motion is good to a fraction of a pixel, so what is left is the detector's)."""
    resid, dof = [], 0.0
    for run in runs:
        p, d, both = _paired(run, detector)
        k = int(both.sum())
        if k < 3:
            continue
        r = d[both] - p[both]
        resid.append(np.linalg.norm(r - np.median(r, axis=0), axis=1))
        dof += k - 1.0
    if not resid or dof < settings.min_frames_for_noise:
        return float(settings.detector_px)
    r = np.concatenate(resid)
    # the fitted offsets took one frame per run
    sigma = float(np.median(r)) / RAYLEIGH_MEDIAN * np.sqrt(len(r) / dof)
    return max(settings.min_detector_px, sigma)


def _solve(detector: np.ndarray, w_det: np.ndarray, step_frames: np.ndarray, steps: np.ndarray,
           w_step: np.ndarray) -> np.ndarray:
    """Weighted least squares of ``x(t) = d(t)`` and ``x(t+1) - x(t) = s`` (tridiagonal, per axis)."""
    n = len(detector)
    diag = np.where(np.isfinite(detector[:, 0]), w_det, 0.0)
    off = np.zeros(n)                     # off[t]: coupling of t and t+1
    rhs = np.where(np.isfinite(detector), detector, 0.0) * diag[:, None]
    np.add.at(diag, step_frames, w_step)
    np.add.at(diag, step_frames + 1, w_step)
    np.add.at(off, step_frames, -w_step)
    np.add.at(rhs, step_frames, -(w_step[:, None] * steps))
    np.add.at(rhs, step_frames + 1, w_step[:, None] * steps)
    bands = np.zeros((3, n))
    bands[0, 1:] = off[:-1]
    bands[1] = diag + 1e-12               # a frame with no data stays solvable; it is masked later
    bands[2, :-1] = off[:-1]
    return solve_banded((1, 1), bands, rhs)


def _anchored(detector: np.ndarray, step_frames: np.ndarray) -> np.ndarray:
    """Frames the solution determines: those linked by tracked steps to at least one detector frame."""
    n = len(detector)
    linked = np.zeros(n, dtype=bool)
    linked[step_frames] = True            # t and t+1 belong to one component
    component = np.concatenate([[0], np.cumsum(~linked[:-1])])
    has_detector = np.zeros(component[-1] + 1, dtype=bool)
    has_detector[component[np.isfinite(detector[:, 0])]] = True
    return has_detector[component]


def fuse_joint(detector: np.ndarray, runs: list[TrackedRun], settings: FuseSettings | None = None) -> JointFusion:
    """The fused path of one joint: ``detector`` (n, 2) pixels with NaN where missing, ``runs`` the
    tracker's runs. Frames neither source reaches stay NaN; with no usable run the detector is returned.
    """
    settings = settings or FuseSettings()
    detector = np.asarray(detector, dtype=float)
    n = len(detector)
    seen = np.isfinite(detector).all(axis=1)
    detector = np.where(seen[:, None], detector, np.nan)
    threshold = settings.agree_sigmas * settings.detector_px
    judged = [_judge_run(r, detector, threshold, settings.run_disagree_share) for r in runs]
    sigma = _detector_noise([r for r in judged if r is not None], detector, settings)
    threshold = settings.agree_sigmas * sigma
    judged = [_judge_run(r, detector, threshold, settings.run_disagree_share) for r in runs]
    kept = [r for r in judged if r is not None]
    dropped = len(runs) - len(kept)
    step_frames, steps = _run_steps(kept, n)
    w_step = np.full(len(steps), 1.0 / settings.tracker_px ** 2)
    x = detector.copy()
    for it in range(max(1, settings.iterations) if steps.size else 0):
        # Huber weights on the detector: full weight within 1.5 sigma, falling as 1/r beyond (a missing
        # detector position has no term, whatever its weight)
        resid = np.linalg.norm(detector - x, axis=1) if it else np.zeros(n)
        w_det = huber(np.nan_to_num(resid), 1.5 * sigma)[0]
        if it:                            # and on the tracked steps: a small slip is one odd step
            r_step = np.linalg.norm(x[step_frames + 1] - x[step_frames] - steps, axis=1)
            w_step = huber(r_step, settings.step_huber * settings.tracker_px)[0] / settings.tracker_px ** 2
        x = _solve(detector, w_det / sigma ** 2, step_frames, steps, w_step)
    if steps.size == 0:
        return JointFusion(detector.copy(), seen.copy(), sigma, 0, dropped)
    x[~_anchored(detector, step_frames)] = np.nan
    resid = np.linalg.norm(detector - x, axis=1)
    agree = seen & (resid <= settings.agree_sigmas * sigma)
    return JointFusion(x, agree, sigma, len(kept), dropped)
