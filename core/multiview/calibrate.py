"""Cameras from the person alone: no board, no markers, just the joints every view sees.

The joints of one person are correspondences between views in every frame, so the views' relative
poses follow as in any two-view geometry:

1. view 2 relative to view 1 from the essential matrix of all joints seen in both (normalised eight
   points in a RANSAC, the pose in front of both cameras), for lens pairs on a grid around a guess,
   keeping the pair whose triangulated bones change length least over the clip;
2. every further view relative to view 1 the same way (view 1's lens kept), its baseline scaled so the
   joints both pairs triangulate lie at the same depths;
3. bundle adjustment (:mod:`.bundle`) of all poses, focal lengths and the joints of a subsample of
   frames, with the person's bone lengths held constant across frames (16 bones, left and right apart;
   20 %, then 5 %, then 1 % of slack): the lengths tie the frames together and are what pins the focal lengths;
4. the metric scale from the person's height (the one thing the images cannot give).

The world of the result is view 1's camera axes (x right, y down, z forward), scaled to metres.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..joint_solve.taylor import fill_missing
from ..nanstats import nanmax, nanmedian
from ..skeleton import class_lengths_from_segments, segment_lengths, standing_height
from .bundle import bundle_adjust as schur_bundle_adjust
from .bundle import focal_sigma
from .cameras import ViewCamera
from .epipolar import essential, sampson
from .triangulate import reprojection_errors, triangulate

#: Frames the bundle adjustment uses (spread over the clip); the rest are triangulated afterwards.
BUNDLE_FRAMES = 120
#: Bone-length slack in the bundle adjustment, as a share of the bone.
LENGTH_SLACK = 0.01
#: The slack the bundle adjustment starts with and tightens to.
SLACK_SCHEDULE = (0.2, 0.05, LENGTH_SLACK)
#: A joint pair off its epipolar line by more than this (pixels) is an outlier to the relative pose.
INLIER_PX = 6.0
#: After the bundle adjustment, observations further than this (or four times the median) from their
#: joint's projection are dropped and the cameras adjusted again.
OUTLIER_PX = 12.0
#: Points a RANSAC hypothesis of the relative pose is scored on.
SCORE_POINTS = 1500
#: Joint pairs the lens grid relates the views from (a subsample, for speed).
GRID_POINTS = 1500
#: Lenses the calibration may end with, as multiples of the guess (1.2 image widths): 0.2-5 times is
#: about 8-200 mm on 36 mm film.
LENS_RANGE = (0.2, 5.0)
#: Lens pairs of the first two views the bundle adjustment starts from (the best by the bones'
#: constancy, each at least 10 % from the others).
STARTS = 3
#: Pixel scale of the robust (Huber) loss.
HUBER_PX = 3.0


def relative_pose(a: np.ndarray, b: np.ndarray, *, threshold: float, seed: int = 0,
                  iterations: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R, t, inliers) of camera b relative to camera a (``X_b = R X_a + t``, |t| = 1) from normalised
    image points (N, 2) of the same world points; ``threshold`` in normalised units."""
    n = len(a)
    if n < 8:
        raise InputError("the views share fewer than 8 joint observations: they cannot be related")
    rng = np.random.default_rng(seed)
    # hypotheses are scored on at most SCORE_POINTS of the points (a long clip has tens of thousands),
    # the winner's inliers then found among all of them
    score = rng.choice(n, min(n, SCORE_POINTS), replace=False)
    sa, sb = a[score], b[score]
    best, best_count = None, -1
    for _ in range(iterations):
        pick = rng.choice(n, 8, replace=False)
        e = essential(a[pick], b[pick])
        count = int((sampson(e, sa, sb) < threshold).sum())
        if count > best_count:
            best, best_count = e, count
    best_in = sampson(best, a, b) < threshold
    e = essential(a[best_in], b[best_in]) if best_in.sum() >= 8 else best
    u, _, vt = np.linalg.svd(e)
    if np.linalg.det(u) < 0:
        u = -u
    if np.linalg.det(vt) < 0:
        vt = -vt
    w = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    choices = [(u @ w @ vt, u[:, 2]), (u @ w @ vt, -u[:, 2]), (u @ w.T @ vt, u[:, 2]), (u @ w.T @ vt, -u[:, 2])]
    scores = []
    for r, t in choices:
        cams = [_cam(np.eye(3), np.zeros(3), 1.0), _cam(r, -r.T @ t, 1.0)]
        pts, _ = triangulate(np.stack([a[best_in], b[best_in]])[:, None], cams, robust=False)
        pts = pts[0]
        za = pts[:, 2]
        zb = (pts @ r.T + t)[:, 2]
        scores.append(np.sum((za > 0) & (zb > 0)))
    r, t = choices[int(np.argmax(scores))]
    return r, t, best_in


def _cam(rotation, position, focal, size=(0.0, 0.0), name="") -> ViewCamera:
    return ViewCamera(name=name, image_size=size, focal_px=focal, rotation=rotation, position=position)


def _bone_spread(points: np.ndarray) -> float:
    """How much the triangulated bones change length over the clip (median relative spread)."""
    seg = segment_lengths(points)
    med = nanmedian(seg, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.abs(seg / med - 1.0)
    return float(nanmedian(nanmedian(relative, axis=0)))


def _lens_pairs(ua, ub, ca, cb, ga, gb, both, *, fixed=(False, False), seed=0, keep=1):
    """Up to ``keep`` lens pairs (f_a, f_b) of two views, best first, each at least 10 % from the
    others: those (on a grid around the guesses) whose relative pose makes the person's bones the most
    constant over the clip."""
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(ua), min(len(ua), GRID_POINTS), replace=False)
    tried: dict = {}

    def spread(fa, fb):
        key = (round(fa, 3), round(fb, 3))
        if key not in tried:
            a, b = (ua - ca) / fa, (ub - cb) / fb
            try:
                r, t, inl = relative_pose(a[pick], b[pick], threshold=INLIER_PX / fb, seed=seed, iterations=120)
            except InputError:
                tried[key] = (np.inf, fa, fb)
                return np.inf
            cams = [_cam(np.eye(3), np.zeros(3), 1.0), _cam(r, -r.T @ t, 1.0)]
            pts = np.full(both.shape + (3,), np.nan)
            tri, _ = triangulate(np.stack([a, b])[:, None], cams, robust=False)
            pts[both] = tri[0]
            tried[key] = (_bone_spread(pts) if inl.mean() > 0.3 else np.inf, fa, fb)
        return tried[key][0]

    # a coarse grid of lens pairs around the guesses, then a finer one around the best
    best = None
    for width, count in ((np.log(2.5), 7), (np.log(2.5) / 3, 5)):
        ca_, cb_ = (ga, gb) if best is None else best[1:]
        steps = np.exp(np.linspace(-width, width, count))
        for fa in ([ga] if fixed[0] else ca_ * steps):
            for fb in ([gb] if fixed[1] else cb_ * steps):
                sc = spread(fa, fb)
                if np.isfinite(sc) and (best is None or sc < best[0]):
                    best = (sc, fa, fb)
    if best is None:
        raise InputError("the views could not be related from the joints they share")
    pairs: list = []
    for _, fa, fb in sorted(v for v in tried.values() if np.isfinite(v[0])):
        if all(max(abs(np.log(fa / pa)), abs(np.log(fb / pb))) > np.log(1.1) for pa, pb in pairs):
            pairs.append((fa, fb))
        if len(pairs) == keep:
            break
    return pairs


def _place_cameras(pixels, cams, f1, f2, guess, fixed, seed, memo: dict):
    """Every camera from a lens pair of the first two views: view 2 by its essential matrix, each
    further view against view 1 (view 1's lens kept, its own searched), its baseline scaled so the
    joints both pairs triangulate lie at the same depths. Returns (cameras, view 2's inlier share).
    ``memo`` keeps each further view's relation to view 1 per view-1 lens across calls."""
    names = [c.name for c in cams]
    both = np.isfinite(pixels[0]).all(-1) & np.isfinite(pixels[1]).all(-1)
    c0, c1 = cams[0].centre, cams[1].centre
    r, t, inliers = relative_pose((pixels[0][both] - c0) / f1, (pixels[1][both] - c1) / f2,
                                  threshold=INLIER_PX / f2, seed=seed)
    cams = list(cams)
    cams[0] = ViewCamera(names[0], cams[0].image_size, f1, np.eye(3), np.zeros(3))
    cams[1] = ViewCamera(names[1], cams[1].image_size, f2, r, -r.T @ t)
    pts, _ = triangulate(pixels[:2], cams[:2], robust=False)
    for k in range(2, len(cams)):
        pair = np.isfinite(pixels[0]).all(-1) & np.isfinite(pixels[k]).all(-1)
        if pair.sum() < 12:
            raise InputError(f"{names[k]} shares too few joints with {names[0]} to be placed")
        key = (k, round(float(f1), 3))
        if key not in memo:
            (_, fk), = _lens_pairs(pixels[0][pair], pixels[k][pair], c0, cams[k].centre, f1, guess[k], pair,
                                   fixed=(True, fixed[k]), seed=seed)
            a, b = (pixels[0][pair] - c0) / f1, (pixels[k][pair] - cams[k].centre) / fk
            memo[key] = (fk, *relative_pose(a, b, threshold=INLIER_PX / fk, seed=seed)[:2])
        fk, rk, tk = memo[key]
        trial = ViewCamera(names[k], cams[k].image_size, fk, rk, -rk.T @ tk)
        pk, _ = triangulate(pixels[[0, k]], [cams[0], trial], robust=False)
        common = np.isfinite(pk).all(-1) & np.isfinite(pts).all(-1)
        if common.sum() < 12:
            raise InputError(f"{names[k]} shares too few joints with {names[0]} and {names[1]} to be placed")
        scale = float(np.median(pts[common][:, 2] / pk[common][:, 2]))
        cams[k] = ViewCamera(names[k], cams[k].image_size, fk, rk, -rk.T @ tk * scale)
    return cams, float(inliers.mean())


def _plausible(points: np.ndarray, pixels: np.ndarray, cams) -> np.ndarray:
    """``points`` (F, 17, 3) with the implausible ones made NaN: off their observations by over
    :data:`OUTLIER_PX` (or four times the median), or further from their frame's middle than twice the
    body's usual extent (a limb exchanged in one of two views triangulates far
    off, and such a start costs more than all the rest and drags the lenses)."""
    pts = points.copy()
    bad = _far_observations(pts, pixels, cams).any(axis=0)
    middle = nanmedian(pts, axis=1)                                           # (F, 3)
    reach = np.linalg.norm(pts - middle[:, None], axis=-1)
    bad |= np.isfinite(reach) & (reach > 2.0 * nanmedian(nanmax(reach, axis=1)))
    if bad.mean() > 0.5:
        return pts                        # the rough cameras, not the points, are what is off: keep them all
    pts[bad] = np.nan
    return pts


def _far_observations(points: np.ndarray, pixels: np.ndarray, cams) -> np.ndarray:
    """(V, F, 17) bool: observations further than :data:`OUTLIER_PX`, or four times the median, from
    their point's projection (the relative limit: cameras that are only roughly right yet)."""
    err = reprojection_errors(points, pixels, cams)
    limit = max(OUTLIER_PX, 4.0 * float(nanmedian(err)))
    return np.isfinite(err) & (err > limit)


def _adjust(cams, pixels_sub, schedule=SLACK_SCHEDULE):
    """The bundle adjustment's slack ``schedule`` from ``cams``: (cameras, joints, bone lengths (16), final
    cost, iterations)."""
    pts = fill_missing(_plausible(triangulate(pixels_sub, cams)[0], pixels_sub, cams))
    lengths = nanmedian(segment_lengths(pts), axis=0)
    ok = np.isfinite(lengths) & (lengths > 0)
    if not ok.any():
        raise InputError("the views show no bone of the person in both views")
    lengths = np.where(ok, lengths, float(np.median(lengths[ok])))
    iterations, cost = 0, np.inf
    for slack in schedule:                # loose first: a wrong lens guess bends every bone at the start
        cams, pts, lengths, bundle = schur_bundle_adjust(cams, pixels_sub, pts, lengths, slack=slack,
                                                         huber_px=HUBER_PX)
        iterations += bundle["iterations"]
        cost = bundle["cost"]
    return cams, pts, lengths, cost, iterations


def calibrate_from_person(pixels: np.ndarray, image_sizes: list[tuple[float, float]], height_m: float,
                          focal_px: list[float | None] | None = None, names: list[str] | None = None,
                          seed: int = 0) -> tuple[list[ViewCamera], dict]:
    """Cameras (world: view 1's axes, metres) from the joints' pixels (V, F, 17, 2) of every view.

    ``focal_px``: per view, a known focal length in pixels or None (guessed, then adjusted).
    The bundle adjustment starts from the :data:`STARTS` best lens pairs of the first two views and
    keeps the one that ends fitting best (a detector's errors can make the bones' constancy prefer a
    wrong pair, from which the adjustment does not find its way).
    Returns (cameras, report) with the bundle adjustment's numbers."""
    v, f = pixels.shape[:2]
    if v < 2:
        raise InputError("multi-view estimation needs at least two views")
    names = names or [f"view {k + 1}" for k in range(v)]
    guess = [(fp if fp else 1.2 * max(sz)) for fp, sz in zip(focal_px or [None] * v, image_sizes)]
    fixed = [bool(focal_px and focal_px[k]) for k in range(v)]
    start = [ViewCamera(names[k], tuple(image_sizes[k]), guess[k], np.eye(3), np.zeros(3)) for k in range(v)]
    both = np.isfinite(pixels[0]).all(-1) & np.isfinite(pixels[1]).all(-1)
    pairs = _lens_pairs(pixels[0][both], pixels[1][both], start[0].centre, start[1].centre, guess[0], guess[1],
                        both, fixed=(fixed[0], fixed[1]), seed=seed, keep=STARTS)
    sub = np.unique(np.linspace(0, f - 1, min(f, BUNDLE_FRAMES)).round().astype(int))
    best, costs, memo, iterations, failure = None, [], {}, 0, None
    for f1, f2 in pairs:
        try:
            cams, inliers = _place_cameras(pixels, start, f1, f2, guess, fixed, seed, memo)
            cams, pts_sub, lengths, cost, its = _adjust(cams, pixels[:, sub])
        except InputError as exc:          # this start could not place or measure the person
            failure = exc
            continue
        iterations += its
        if any(not LENS_RANGE[0] <= c.focal_px / g <= LENS_RANGE[1] for c, g in zip(cams, guess)):
            cost = np.inf                  # a lens ran off (the adjustment found a degenerate fit)
        costs.append(float(cost))
        if best is None or cost < best[0]:
            best = (cost, cams, pts_sub, lengths, inliers)
    if best is None and failure is not None:
        raise failure
    if best is None or not np.isfinite(best[0]):
        raise InputError("the cameras could not be found from the person: every start ended with a lens out of "
                         "range; give a calibration file")
    _, cams, pts_sub, lengths, inliers = best
    # what the cleaning left (a limb exchanged in one view, a miss) pulls the cameras: observations far
    # from where the adjusted cameras put their joint are dropped and the last adjustment run again
    sub_px = pixels[:, sub].copy()
    far = _far_observations(pts_sub, sub_px, cams)
    if far.any():
        sub_px[far] = np.nan
        cams, pts_sub, lengths, bundle = schur_bundle_adjust(cams, sub_px, pts_sub, lengths, slack=LENGTH_SLACK,
                                                             huber_px=HUBER_PX)
        iterations += bundle["iterations"]
    sigma = focal_sigma(cams, sub_px, pts_sub, lengths, slack=LENGTH_SLACK, huber_px=HUBER_PX)
    classes = class_lengths_from_segments(lengths)
    scale = height_m / float(standing_height(classes))
    cams = [ViewCamera(c.name, c.image_size, c.focal_px, c.rotation, c.position * scale) for c in cams]
    report = {"essential_inliers": inliers, "bundle_frames": int(len(sub)),
              "class_lengths_m": (classes * scale).tolist(), "focal_guess_px": guess,
              "bundle_iterations": iterations, "dropped_observations": int(far.sum()),
              "start_costs": costs,
              "focal_sigma_pct": None if sigma is None else [100.0 * v for v in sigma]}
    return cams, report


__all__ = ["BUNDLE_FRAMES", "calibrate_from_person", "relative_pose"]
