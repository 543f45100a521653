"""Second look after a solve: points the solved figure and camera cannot explain.

The cleaning before the solve sees 2D evidence only; an outlier that stays near the body, a limb
exchange the continuity search missed, a wrist on a table leg for a whole second all get past it.
Once a method has put a figure of fixed proportions through a camera, such points stand out: their
reprojection residual is far larger than the rest.  :func:`residual_outliers` marks them, and
:func:`core.estimate.estimate` solves once more without them.

It runs only on tracks whose cleaning found a detector's gross errors: on clean tracks the points a
solve leaves unexplained are true ones its priors cannot follow (fast wrists), and a second solve
without them measured worse.  A point is marked when its residual exceeds both a share of the
figure's image size (so a small figure's pixel noise is not taken for an error) and a multiple of
that joint's typical residual over the clip (wrists and ankles jitter more than hips).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..nanstats import RAYLEIGH_MEDIAN, nanmedian
from ..result import Estimate
from ..self_check.reprojection import camera_points, reprojection_residuals
from ..tracks import Tracks
from .body_scale import body_scale


@dataclass(frozen=True)
class ResidualSettings:
    """Chosen on the tuning half of ``bench/robust_bench.py``'s target cases (``docs/robustness.md``)."""

    #: Smallest residual that can mark a point, in body scales (the median 2D segment length).
    scale_share: float = 0.3
    #: ... and in multiples of the joint's own noise level (its median residual / 1.177).
    sigmas: float = 4.0
    #: The second pass runs only when the cleaning rejected at least this share of the points: on the
    #: tuning half every case with a detector's errors had 0.7 % or more, every clean one 0.03 % or less.
    min_gross_share: float = 0.002


DEFAULT_RESIDUAL = ResidualSettings()


def found_detector_errors(report, tracks: Tracks, settings: ResidualSettings = DEFAULT_RESIDUAL) -> bool:
    """Whether the cleaning ``report`` of ``tracks`` (the raw ones) saw a detector's gross errors: the
    gate of the second pass, and of everything else that reads a detector's tracks more warily."""
    return report is not None and report.gross_share(int(tracks.present.sum())) >= settings.min_gross_share


def residual_outliers(tracks: Tracks, est: Estimate,
                      settings: ResidualSettings = DEFAULT_RESIDUAL) -> np.ndarray | None:
    """(F, 17) bool: observed points of ``tracks`` the estimate leaves unexplained; None when the
    estimate has no per-frame 3D joints to reproject (the paper's method)."""
    if len(est.frames) != tracks.n_frames or all(f.joints_3d is None for f in est.frames):
        return None
    cam, focal = camera_points(est)
    r = reprojection_residuals(tracks, cam, focal)
    scale = body_scale(tracks.xy, tracks.fps)
    if not np.isfinite(scale).all():
        return None
    sigma = nanmedian(r, axis=0) / RAYLEIGH_MEDIAN                           # (17,)
    sigma = np.where(np.isfinite(sigma), sigma, np.inf)
    limit = np.maximum(settings.scale_share * scale[:, None], settings.sigmas * sigma[None])
    return np.nan_to_num(r, nan=0.0) > limit
