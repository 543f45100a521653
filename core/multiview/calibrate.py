"""Cameras from the person alone: no board, no markers, just the joints every view sees.

The joints of one person are correspondences between views in every frame, so the views' relative
poses follow as in any two-view geometry:

1. view 2 relative to view 1 from the essential matrix of all joints seen in both (normalised eight
   points in a RANSAC, the pose in front of both cameras), for lens pairs on a grid around a guess,
   keeping the pair whose triangulated bones change length least over the clip;
2. every further view relative to view 1 the same way (view 1's lens kept), its baseline scaled so the
   joints both pairs triangulate lie at the same depths;
3. bundle adjustment (:mod:`.bundle`) of all poses, focal lengths and the joints of a subsample of
   frames, with the person's bone lengths held constant across frames (ten class lengths, 20 %, then
   5 %, then 1 % of slack): the lengths tie the frames together and are what pins the focal lengths;
4. the metric scale from the person's height (the one thing the images cannot give).

The world of the result is view 1's camera axes (x right, y down, z forward), scaled to metres.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..nanstats import nanmedian
from ..skeleton import class_lengths_from_segments, segment_lengths, standing_height
from .bundle import bundle_adjust as schur_bundle_adjust
from .cameras import ViewCamera
from .epipolar import essential, sampson
from .triangulate import triangulate

#: Frames the bundle adjustment uses (spread over the clip); the rest are triangulated afterwards.
BUNDLE_FRAMES = 120
#: Bone-length slack in the bundle adjustment, as a share of the bone.
LENGTH_SLACK = 0.01
#: The slack the bundle adjustment starts with and tightens to.
SLACK_SCHEDULE = (0.2, 0.05, LENGTH_SLACK)
#: A joint pair off its epipolar line by more than this (pixels) is an outlier to the relative pose.
INLIER_PX = 6.0
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
    best, best_in = None, np.zeros(n, dtype=bool)
    for _ in range(iterations):
        pick = rng.choice(n, 8, replace=False)
        e = essential(a[pick], b[pick])
        inl = sampson(e, a, b) < threshold
        if inl.sum() > best_in.sum():
            best, best_in = e, inl
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


def _pair_by_bones(ua, ub, ca, cb, ga, gb, both, *, fixed=(False, False), seed=0):
    """(f_a, f_b, R, t, inliers) of the first two views: the lens pair (on a grid around the guesses)
    whose relative pose makes the person's bones the most constant over the clip."""
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(ua), min(len(ua), 1500), replace=False)
    tried: dict = {}

    def spread(fa, fb):
        key = (round(fa, 3), round(fb, 3))
        if key not in tried:
            a, b = (ua - ca) / fa, (ub - cb) / fb
            try:
                r, t, inl = relative_pose(a[pick], b[pick], threshold=INLIER_PX / fb, seed=seed, iterations=120)
            except InputError:
                tried[key] = np.inf
                return np.inf
            cams = [_cam(np.eye(3), np.zeros(3), 1.0), _cam(r, -r.T @ t, 1.0)]
            pts = np.full(both.shape + (3,), np.nan)
            tri, _ = triangulate(np.stack([a, b])[:, None], cams, robust=False)
            pts[both] = tri[0]
            tried[key] = _bone_spread(pts) if inl.mean() > 0.3 else np.inf
        return tried[key]

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
        raise InputError("the first two views could not be related from the joints they share")
    _, fa, fb = best
    r, t, inl = relative_pose((ua - ca) / fa, (ub - cb) / fb, threshold=INLIER_PX / fb, seed=seed)
    return fa, fb, r, t, inl


def calibrate_from_person(pixels: np.ndarray, image_sizes: list[tuple[float, float]], height_m: float,
                          focal_px: list[float | None] | None = None, names: list[str] | None = None,
                          seed: int = 0) -> tuple[list[ViewCamera], dict]:
    """Cameras (world: view 1's axes, metres) from the joints' pixels (V, F, 17, 2) of every view.

    ``focal_px``: per view, a known focal length in pixels or None (guessed, then adjusted).
    Returns (cameras, report) with the bundle adjustment's numbers."""
    v, f = pixels.shape[:2]
    if v < 2:
        raise InputError("multi-view estimation needs at least two views")
    names = names or [f"view {k + 1}" for k in range(v)]
    guess = [(fp if fp else 1.2 * max(sz)) for fp, sz in zip(focal_px or [None] * v, image_sizes)]
    cams = [ViewCamera(names[k], tuple(image_sizes[k]), guess[k], np.eye(3), np.zeros(3)) for k in range(v)]

    def norm(k, uv, focal):
        return (uv - cams[k].centre) / focal

    both = np.isfinite(pixels[0]).all(-1) & np.isfinite(pixels[1]).all(-1)
    f1, f2, r, t, inliers = _pair_by_bones(pixels[0][both], pixels[1][both], cams[0].centre, cams[1].centre,
                                           guess[0], guess[1], both, fixed=(bool(focal_px and focal_px[0]),
                                                                            bool(focal_px and focal_px[1])),
                                           seed=seed)
    cams[0] = ViewCamera(names[0], cams[0].image_size, f1, np.eye(3), np.zeros(3))
    cams[1] = ViewCamera(names[1], cams[1].image_size, f2, r, -r.T @ t)
    pts, _ = triangulate(pixels[:2], cams[:2], robust=False)
    for k in range(2, v):
        # view k against view 1 like view 2 was (view 1's lens kept), then its baseline scaled so the
        # joints both pairs triangulate lie at the same depths from view 1
        pair = np.isfinite(pixels[0]).all(-1) & np.isfinite(pixels[k]).all(-1)
        if pair.sum() < 12:
            raise InputError(f"{names[k]} shares too few joints with {names[0]} to be placed")
        _, fk, rk, tk, _ = _pair_by_bones(pixels[0][pair], pixels[k][pair], cams[0].centre, cams[k].centre,
                                          cams[0].focal_px, guess[k], pair,
                                          fixed=(True, bool(focal_px and focal_px[k])), seed=seed)
        trial = ViewCamera(names[k], cams[k].image_size, fk, rk, -rk.T @ tk)
        pk, _ = triangulate(pixels[[0, k]], [cams[0], trial], robust=False)
        common = np.isfinite(pk).all(-1) & np.isfinite(pts).all(-1)
        if common.sum() < 12:
            raise InputError(f"{names[k]} shares too few joints with {names[0]} and {names[1]} to be placed")
        scale = float(np.median(pts[common][:, 2] / pk[common][:, 2]))
        cams[k] = ViewCamera(names[k], cams[k].image_size, fk, rk, -rk.T @ tk * scale)
    sub = np.unique(np.linspace(0, f - 1, min(f, BUNDLE_FRAMES)).round().astype(int))
    pts_sub, _ = triangulate(pixels[:, sub], cams)
    pts_sub = np.where(np.isfinite(pts_sub), pts_sub, np.nanmean(pts_sub.reshape(-1, 3), axis=0))
    lengths = nanmedian(class_lengths_from_segments(segment_lengths(pts_sub)), axis=0)
    lengths = np.where(np.isfinite(lengths) & (lengths > 0), lengths, nanmedian(lengths))
    iterations = 0
    for slack in SLACK_SCHEDULE:          # loose first: a wrong lens guess bends every bone at the start
        cams, pts_sub, lengths, bundle = schur_bundle_adjust(cams, pixels[:, sub], pts_sub, lengths, slack=slack,
                                                             huber_px=HUBER_PX)
        iterations += bundle["iterations"]
    scale = height_m / float(standing_height(lengths))
    cams = [ViewCamera(c.name, c.image_size, c.focal_px, c.rotation, c.position * scale) for c in cams]
    report = {"essential_inliers": float(inliers.mean()), "bundle_frames": int(len(sub)),
              "class_lengths_m": (lengths * scale).tolist(), "focal_guess_px": guess,
              "bundle_iterations": iterations}
    return cams, report


__all__ = ["BUNDLE_FRAMES", "calibrate_from_person", "relative_pose"]
