"""Frame offsets between views: which frame of one view shows the moment another view's frame 0 shows.

Phones started by hand do not start together.  The joints give the offset without any calibration:
at the right offset the same joints in the two views are images of the same 3D points, so one
fundamental matrix explains them all (a RANSAC fit leaves a small epipolar error); at a wrong offset
the person has moved between the two images and no single matrix does.  Every whole-frame offset
within ``max_s`` seconds is tried and the one with the smallest median epipolar (Sampson) error wins.

A repeated movement can leave two answers: a steady walk a gait cycle later is the same pose moved
along, and a second camera moved along with it would see the same pictures, so a matrix explains the
pairs at the wrong offset as well as at the right one.  The best answer is then said to be ambiguous
(:func:`ambiguity_warning`) when another one, more than :data:`SEPARATION_FRAMES` away, fits within
:data:`AMBIGUITY_MARGIN` of it.  Still scene points both views track under the same names settle it
when there are eight or more (not all on one plane): they fix the matrix whatever the offset, and
the joints at a wrong offset do not keep to it.
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
    return epipolar_fit(a, b, rng=rng, iterations=iterations)[0]


def epipolar_fit(a: np.ndarray, b: np.ndarray, *, rng: np.random.Generator,
                 iterations: int = 80) -> tuple[float, np.ndarray | None]:
    """(:func:`epipolar_error`, the matrix behind it or None)."""
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
        return np.inf, None
    for _ in range(2):
        inl = sampson(best_f, a, b) < 3.0 * max(best, 0.1)
        if inl.sum() < 8:
            break
        best_f = fundamental(a[inl], b[inl])
        best = min(best, float(np.median(sampson(best_f, a, b))))
    return best, best_f


#: Offsets within this many frames of each other are one answer (the fit changes little in a frame or
#: two); a competitor must lie farther from the best to count as another answer.
SEPARATION_FRAMES = 2
#: The best answer is called ambiguous when a distinct competitor fits within this share of its error
#: (second-best error <= best * (1 + margin)).  Chosen on the tune half of bench/sync_bench.py (0005_Jogging,
#: 131_01; with --steady also walk-left and neutral made perfectly periodic): the smallest margin of its grid
#: that warned every wrong answer there (9, the worst at a ratio of 1.06; 0.05 missed 2), with 1 false alarm
#: in 16 natural cases.  On the report half: every wrong answer warned (3 of 3 natural, 15 of 15 steady),
#: 8 false alarms in 69 natural cases where the right one was taken (docs/multiview.md).
AMBIGUITY_MARGIN = 0.10
#: Scene points are trusted only when the best offset's joints keep to their matrix within this many
#: times (plus half a pixel) the error of the joints' own matrix there.
STATIC_TRUST = 2.0
#: Local minima of the rough scores (over +-SEPARATION_FRAMES) looked at again, best first.
CANDIDATE_MINIMA = 4


def static_pairs(first: Tracks, other: Tracks) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Pixel pairs of the static scene points both views track under one name (their median place over
    the clip: still cameras see them still), and the names; empty when there are none."""
    if first.static is None or other.static is None:
        return np.empty((0, 2)), np.empty((0, 2)), []
    names = [n for n in first.static.names if n in other.static.names]
    a, b, kept = [], [], []
    for name in names:
        pa = first.static.xy[:, first.static.names.index(name)]
        pb = other.static.xy[:, other.static.names.index(name)]
        if np.isfinite(pa).all(axis=-1).any() and np.isfinite(pb).all(axis=-1).any():
            a.append(np.nanmedian(pa, axis=0))
            b.append(np.nanmedian(pb, axis=0))
            kept.append(name)
    return np.array(a).reshape(-1, 2), np.array(b).reshape(-1, 2), kept


def _static_matrix(sa: np.ndarray, sb: np.ndarray) -> np.ndarray | None:
    """The fundamental matrix of the scene points both views track (eight or more, not on one plane: a
    floor's points alone leave it free), or None when they cannot give one."""
    if len(sa) < 8:
        return None
    try:
        return fundamental(sa, sb)
    except np.linalg.LinAlgError:
        return None


def frame_offset(first: Tracks, other: Tracks, *, max_s: float = 2.0, seed: int = 0,
                 max_points: int = 1500, margin: float = AMBIGUITY_MARGIN) -> tuple[int, dict]:
    """(d, report): ``other``'s frame ``t + d`` shows the moment ``first``'s frame ``t`` shows.

    ``report``: ``error_px`` of the best offset; ``second_offset`` and ``second_px``, the best offset
    farther than :data:`SEPARATION_FRAMES` from it and its error (None when none was judged);
    ``ambiguous`` when that one fits within ``margin`` of the best (a walk repeats every step: a
    gait cycle later the person stands in the same pose, moved along, and a matrix of a camera moved
    along too explains the pairs as well); ``static_points``, how many still scene points both views
    track under one name were used (eight or more, not all on one plane: they fix the matrix, which the
    joints at a wrong offset do not keep to); ``static_refused`` when there were such points but the
    best offset's joints kept to their matrix far worse than to their own (:data:`STATIC_TRUST`: the
    points pin it badly), so the joints decided alone; ``tried``."""
    if abs(first.fps - other.fps) > 1e-3 * first.fps:
        raise InputError("views with different frame rates cannot be synchronised: resample them first")
    rng = np.random.default_rng(seed)
    reach = int(round(max_s * first.fps))
    # a short clip needs most of itself in common instead of the full MIN_OVERLAP_S
    need = max(8, min(int(MIN_OVERLAP_S * first.fps), int(0.6 * min(first.n_frames, other.n_frames))))
    sa, sb, names = static_pairs(first, other)
    # still scene points fix the two cameras' epipolar geometry whatever the offset; then an offset is
    # judged by how well its joint pairs keep to it (a cycle away they need a camera moved along)
    f_static = _static_matrix(sa, sb)

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

    def joint_score(d, limit, iterations):
        ab = pairs(d, limit)
        return None if ab is None else epipolar_error(*ab, rng=rng, iterations=iterations)

    def static_score(d, limit, iterations):
        ab = pairs(d, limit)
        return None if ab is None else float(np.median(sampson(f_static, *ab)))

    def search(score):
        """Every offset roughly; then the best local minima of that curve, each with its neighbours,
        again with more points and more tries."""
        rough = {}
        for d in range(-reach, reach + 1):
            value = score(d, max_points // 3, 30)
            if value is not None:
                rough[d] = value
        minima = [d for d in rough if all(rough[d] <= rough.get(e, np.inf)
                                          for e in range(d - SEPARATION_FRAMES, d + SEPARATION_FRAMES + 1))]
        scores = {}
        for m in sorted(minima, key=rough.get)[:CANDIDATE_MINIMA]:
            for d in (m - 1, m, m + 1):
                if d in rough and d not in scores:
                    scores[d] = score(d, max_points, 80)
        if not scores:
            raise InputError("the views do not overlap long enough to be synchronised")
        return scores, len(rough)

    used_static = 0
    if f_static is not None:
        scores, tried = search(static_score)
        best = min(scores, key=scores.get)
        # scene points that pin the matrix badly (too few, bunched, nearly on one plane) leave even the
        # best offset's joints far from it: then they are not trusted, and the joints decide alone
        if scores[best] <= STATIC_TRUST * joint_score(best, max_points, 80) + 0.5:
            used_static = len(names)
    if not used_static:
        scores, tried = search(joint_score)
    best = min(scores, key=scores.get)
    others = [d for d in scores if abs(d - best) > SEPARATION_FRAMES]
    second = min(others, key=scores.get) if others else None
    second_px = scores[second] if second is not None else None
    ambiguous = second is not None and second_px <= scores[best] * (1.0 + margin)
    return best, {"offset": best, "error_px": scores[best], "second_offset": second, "second_px": second_px,
                  "ambiguous": bool(ambiguous), "static_points": used_static,
                  "static_refused": bool(f_static is not None and not used_static), "tried": tried}


def ambiguity_warning(view_name: str, first_name: str, report: dict, fps: float) -> str | None:
    """The warning for an ambiguous offset (:func:`frame_offset`), naming both answers and their fits."""
    if not report.get("ambiguous"):
        return None
    best, second = report["offset"], report["second_offset"]
    return (f"views: the frame offset of {view_name} against {first_name} is ambiguous: {best:+d} frames fits "
            f"{report['error_px']:.2f} px and {second:+d} frames ({(second - best) / fps:+.2f} s away) "
            f"{report['second_px']:.2f} px (a repeated movement, such as a walk's steps, looks the same a cycle "
            f"later); {best:+d} was taken - if you know the offset, give it (estimate-multiview --offsets) or cut "
            f"the views to start together; still scene points tracked in both views under the same names "
            f"(eight or more, not all on one plane) settle it")


def aligned_pixels(view: Tracks, offset: int, n_frames: int) -> np.ndarray:
    """(n_frames, 17, 2) pixels of ``view`` on the first view's clock (NaN where it has no frame)."""
    out = np.full((n_frames, view.xy.shape[1], 2), np.nan)
    t = np.arange(n_frames) + offset
    ok = (t >= 0) & (t < view.n_frames)
    src = np.where(view.present[..., None], view.xy, np.nan)
    out[ok] = src[t[ok]]
    return out
