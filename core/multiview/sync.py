"""Frame offsets between views: which frame of one view shows the moment another view's frame 0 shows.

Phones started by hand do not start together.  The joints give the offset without any calibration:
at the right offset the same joints in the two views are images of the same 3D points, so one
fundamental matrix explains them all (a RANSAC fit leaves a small epipolar error); at a wrong offset
the person has moved between the two images and no single matrix does.  Every whole-frame offset
within ``max_s`` seconds is tried and the one with the smallest median epipolar (Sampson) error wins.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..tracks import Tracks
from .epipolar import fundamental, sampson

#: Shortest overlap (seconds) an offset must leave between the two views to be judged (for clips
#: shorter than that, 60 % of the shorter view).
MIN_OVERLAP_S = 2.0


def epipolar_error(a: np.ndarray, b: np.ndarray, *, rng: np.random.Generator, iterations: int = 80) -> float:
    """Median Sampson error (pixels) of the fundamental matrix a RANSAC finds for the pairs, refitted on
    its inliers (the refit takes the RANSAC's luck out of the comparison between offsets)."""
    n = len(a)
    best, best_f = np.inf, None
    for _ in range(iterations):
        pick = rng.choice(n, 8, replace=False)
        try:
            f = fundamental(a[pick], b[pick])
        except np.linalg.LinAlgError:
            continue
        err = float(np.median(sampson(f, a, b)))
        if err < best:
            best, best_f = err, f
    if best_f is None:
        return np.inf
    for _ in range(2):
        inl = sampson(best_f, a, b) < 3.0 * max(best, 0.1)
        if inl.sum() < 8:
            break
        best_f = fundamental(a[inl], b[inl])
        best = min(best, float(np.median(sampson(best_f, a, b))))
    return best


def frame_offset(first: Tracks, other: Tracks, *, max_s: float = 2.0, seed: int = 0,
                 max_points: int = 1500) -> tuple[int, dict]:
    """(d, report): ``other``'s frame ``t + d`` shows the moment ``first``'s frame ``t`` shows.

    ``report``: the error of the best and of the second-best offset (pixels), and how many offsets
    were tried."""
    if abs(first.fps - other.fps) > 1e-3 * first.fps:
        raise InputError("views with different frame rates cannot be synchronised: resample them first")
    rng = np.random.default_rng(seed)
    reach = int(round(max_s * first.fps))
    # a short clip needs most of itself in common instead of the full MIN_OVERLAP_S
    need = max(8, min(int(MIN_OVERLAP_S * first.fps), int(0.6 * min(first.n_frames, other.n_frames))))

    def pairs(d, limit):
        lo, hi = max(0, -d), min(first.n_frames, other.n_frames - d)
        if hi - lo < need:
            return None
        ok = first.present[lo:hi] & other.present[lo + d:hi + d]
        a, b = first.xy[lo:hi][ok], other.xy[lo + d:hi + d][ok]
        if len(a) < 16:
            return None
        if len(a) > limit:
            keep = rng.choice(len(a), limit, replace=False)
            a, b = a[keep], b[keep]
        return a, b

    # every offset roughly, then the five best again with more points and more tries
    rough = {}
    for d in range(-reach, reach + 1):
        ab = pairs(d, max_points // 3)
        if ab is not None:
            rough[d] = epipolar_error(*ab, rng=rng, iterations=30)
    scores = {}
    for d in sorted(rough, key=rough.get)[:5]:
        scores[d] = epipolar_error(*pairs(d, max_points), rng=rng)
    if not scores:
        raise InputError("the views do not overlap long enough to be synchronised")
    ranked = sorted(scores, key=scores.get)
    best = ranked[0]
    return best, {"error_px": scores[best], "second_px": scores[ranked[1]] if len(ranked) > 1 else None,
                  "tried": len(rough)}


def aligned_pixels(view: Tracks, offset: int, n_frames: int) -> np.ndarray:
    """(n_frames, 17, 2) pixels of ``view`` on the first view's clock (NaN where it has no frame)."""
    out = np.full((n_frames, view.xy.shape[1], 2), np.nan)
    t = np.arange(n_frames) + offset
    ok = (t >= 0) & (t < view.n_frames)
    src = np.where(view.present[..., None], view.xy, np.nan)
    out[ok] = src[t[ok]]
    return out
