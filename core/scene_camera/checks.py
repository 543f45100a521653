"""What the scene camera's own residuals and geometry say about it: is the focal length determined,
does the camera translate.

* **Focal length.**  A camera that only pans a little sees the same image motion at any focal
  length (a pan of ``a`` moves the picture by ``f a``), so the focal length is determined only by
  the perspective change of a larger turn.  It is reported determined when the optical axis turns
  at least :data:`MIN_TURN_DEG` over the clip *and* the adjustment's own standard deviation of
  ``log f`` (the data alone) is at most :data:`MAX_LOG_FOCAL_SIGMA`.
* **Translation.**  A camera that moves (a walking operator) shows parallax between near and far
  points, which no rotation explains.  The residuals' slow part is that parallax; their
  frame-to-frame jitter is the tracking noise.  The camera is reported translating when the slow
  part exceeds :data:`PARALLAX_PX` and the noise.
"""

from __future__ import annotations

import numpy as np

from ..nanstats import second_difference_sigma

MIN_TURN_DEG = 10.0
MAX_LOG_FOCAL_SIGMA = 0.01
PARALLAX_PX = 1.5


def turn_deg(R: np.ndarray) -> float:
    """Largest angle (degrees) between two frames' optical axes (rows ``R[i, 2]`` in frame-0 axes)."""
    axes = R[:, 2, :]
    if axes.shape[0] > 400:                       # the extreme pairs are found among a thinned set
        axes = axes[np.unique(np.linspace(0, axes.shape[0] - 1, 400).round().astype(int))]
    cos = np.clip(axes @ axes.T, -1.0, 1.0)
    return float(np.degrees(np.arccos(cos.min())))


def focal_determinacy(turn: float, log_focal_sigma: float) -> tuple[bool, str]:
    """(determined, reason when not)."""
    if turn < MIN_TURN_DEG:
        return False, (f"the camera turns only {turn:.1f} degrees over the clip; the focal length needs "
                       f"{MIN_TURN_DEG:g} or more")
    if not np.isfinite(log_focal_sigma) or log_focal_sigma > MAX_LOG_FOCAL_SIGMA:
        pct = 100.0 * log_focal_sigma if np.isfinite(log_focal_sigma) else float("inf")
        return False, (f"the background points leave the focal length uncertain by {pct:.1f} % "
                       f"(at most {100 * MAX_LOG_FOCAL_SIGMA:g} % trusted)")
    return True, ""


def noise_and_parallax(residuals: np.ndarray, frame: np.ndarray, point: np.ndarray,
                       keep: np.ndarray) -> tuple[float, float]:
    """(noise px, parallax px) from the residuals (m, 2) of observations ``keep`` (see module docstring).

    The noise comes from second differences along each point's track over consecutive frames (white
    noise: 6 sigma^2); the parallax is what remains of the residuals' (robust) mean square once that is
    taken off.
    """
    e, fr, pt = residuals[keep], frame[keep], point[keep]
    if e.shape[0] < 3:
        return float("nan"), float("nan")
    order = np.lexsort((fr, pt))
    e, fr, pt = e[order], fr[order], pt[order]
    consecutive = (pt[1:-1] == pt[:-2]) & (pt[1:-1] == pt[2:]) & (fr[1:-1] - fr[:-2] == 1) & (fr[2:] - fr[1:-1] == 1)
    d2 = (e[2:] - 2 * e[1:-1] + e[:-2])[consecutive]
    if d2.shape[0] < 10:
        return float("nan"), float("nan")
    noise = second_difference_sigma(d2)
    # per-axis mean square from the median squared norm (chi-square, 2 degrees of freedom: median 2 ln 2),
    # so a few slipping tracks do not pass for a moving camera
    ms = float(np.median(np.sum(e ** 2, axis=1))) / (2.0 * np.log(2.0))
    return noise, float(np.sqrt(max(ms - noise ** 2, 0.0)))


def translating(noise: float, parallax: float) -> bool:
    return bool(np.isfinite(parallax) and parallax > max(PARALLAX_PX, noise))
