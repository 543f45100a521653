"""Gross outliers: a joint the detector put somewhere else for a few frames.

A point is an outlier when it is far from the running median of its own track (a window short in
seconds, so a 1-3 frame excursion is a minority in it) *and* it stretches one of its 2D bones far
beyond that bone's usual image length.  The two tests together spare a fast kick or punch (far from
the median, bones normal) and a joint where the limb really is (bones normal); a point very far from
its track is rejected on that alone.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..nanstats import nanmedian
from ..skeleton import N_JOINTS, SEGMENTS
from .body_scale import segment_lengths_2d


def running_median(xy: np.ndarray, half: int) -> np.ndarray:
    """(F, J, 2) NaN-aware running median over ``2 * half + 1`` frames (edges padded with NaN)."""
    pad = np.full((half,) + xy.shape[2:], np.nan)
    out = np.full_like(xy, np.nan)
    for j in range(xy.shape[1]):          # one joint at a time bounds the memory of the window view
        win = sliding_window_view(np.concatenate([pad, xy[:, j], pad], axis=0), 2 * half + 1, axis=0)
        ok = np.isfinite(win).any(axis=-1)
        if ok.any():
            med = np.nanmedian(win[ok], axis=-1)
            out[:, j][ok] = med
    return out


def bone_stretch(xy: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(F, 17): the largest ratio of a joint's 2D bone lengths to their clip medians (both per body scale)."""
    seg = segment_lengths_2d(xy) / scale[:, None]
    typical = nanmedian(seg, axis=0)
    typical = np.where(np.isfinite(typical) & (typical > 0), typical, np.nan)
    ratio = seg / typical[None]
    out = np.zeros((xy.shape[0], N_JOINTS))
    for s, (p, c) in enumerate(SEGMENTS):
        r = np.where(np.isfinite(ratio[:, s]), ratio[:, s], 0.0)
        out[:, p] = np.maximum(out[:, p], r)
        out[:, c] = np.maximum(out[:, c], r)
    return out


def find_outliers(xy: np.ndarray, scale: np.ndarray, fps: float, *, window_s: float, residual: float,
                  stretch: float, residual_alone: float) -> np.ndarray:
    """(F, 17) bool: gross outliers (thresholds in body scales; see the module docstring)."""
    half = max(3, int(round(window_s * fps / 2.0)))
    med = running_median(xy, half)
    with np.errstate(invalid="ignore"):
        r = np.linalg.norm(xy - med, axis=-1) / scale[:, None]
        b = bone_stretch(xy, scale)
        out = ((r > residual) & (b > stretch)) | (r > residual_alone)
    return out & np.isfinite(xy).all(axis=-1)
