"""Which frames of an estimate need a look: rejected or swapped input, poor fit.

Pure data, so the timeline markers in Blender (``blender/review``) and the headless report say the same.
"""

from __future__ import annotations

import numpy as np

from ..nanstats import nanmedian
from ..result import Estimate
from ..runs import run_starts
from ..self_check.checks import SelfCheckSettings

REJECTED = "input: rejected joints"
SWAPPED = "input: left/right undone"
POOR_FIT = "fit: poor"


def reprojection_series(est: Estimate) -> np.ndarray:
    """(F,) mean reprojection error per frame, NaN where the frame has none."""
    return np.array([np.nan if fr.reprojection_px is None else float(fr.reprojection_px) for fr in est.frames])


def poor_fit_limit_px(est: Estimate) -> float | None:
    """The per-frame reprojection error above which a frame fits poorly (None: no errors known)."""
    rep = reprojection_series(est)
    if not np.isfinite(rep).any():
        return None
    s = SelfCheckSettings()
    return max(s.fit_floor_px, s.poor_frame_ratio * float(nanmedian(rep)))


def poor_fit(est: Estimate) -> np.ndarray:
    """(F,) bool: frames whose mean reprojection error is over the self-check's limit."""
    rep = reprojection_series(est)
    limit = poor_fit_limit_px(est)
    if limit is None:
        return np.zeros(len(rep), dtype=bool)
    return np.isfinite(rep) & (rep > limit)


def problem_masks(est: Estimate) -> dict[str, np.ndarray]:
    """problem name -> (F,) bool of the frames it concerns."""
    return {REJECTED: np.array([bool(fr.rejected) for fr in est.frames], dtype=bool),
            SWAPPED: np.array([bool(fr.swapped) for fr in est.frames], dtype=bool),
            POOR_FIT: poor_fit(est)}


def problem_starts(est: Estimate) -> list[tuple[str, int]]:
    """(problem name, estimate frame) of the first frame of every run of a problem."""
    return [(name, i) for name, mask in problem_masks(est).items() for i in run_starts(mask)]
