"""The figure's size in the image, per frame: the unit of every cleaning threshold.

The median of a frame's 2D segment lengths is robust to one wrong joint (it touches at most three
of the 16 segments), and a running median over a second removes what is left; frames with too few
segments borrow from their neighbours.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import median_filter

from ..nanstats import nanmedian
from ..skeleton import SEGMENTS

#: A frame needs this many measurable segments to give its own scale.
MIN_SEGMENTS = 5


def segment_lengths_2d(xy: np.ndarray) -> np.ndarray:
    """(F, 16) image lengths of the segments, NaN where a joint is missing."""
    parents = np.array([p for p, _ in SEGMENTS])
    children = np.array([c for _, c in SEGMENTS])
    return np.linalg.norm(xy[:, children] - xy[:, parents], axis=-1)


def body_scale(xy: np.ndarray, fps: float, smooth_s: float = 1.0) -> np.ndarray:
    """(F,) image size of the figure in pixels (median 2D segment length, smoothed over ``smooth_s``)."""
    seg = segment_lengths_2d(xy)
    count = np.isfinite(seg).sum(axis=1)
    raw = np.where(count >= MIN_SEGMENTS, nanmedian(seg, axis=1), np.nan)
    n = raw.size
    ok = np.isfinite(raw) & (raw > 0)
    if not ok.any():
        return np.full(n, np.nan)
    t = np.arange(n)
    filled = np.interp(t, t[ok], raw[ok])
    size = max(1, int(round(smooth_s * fps)) | 1)
    return median_filter(filled, size=min(size, 2 * n - 1 if n > 1 else 1), mode="nearest")
