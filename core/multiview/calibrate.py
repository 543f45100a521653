"""Cameras from the person alone: no board, no markers, just the joints every view sees.

The joints of one person are correspondences between views in every frame, so the views' relative
poses follow as in any two-view geometry:

1. view 2 relative to view 1 from the essential matrix of all joints seen in both (normalised eight
   points in a RANSAC, the pose in front of both cameras), for lens pairs on a grid around a guess,
   keeping the pair whose triangulated bones change length least over the clip;
2. every further view relative to view 1 the same way (view 1's lens kept), its baseline scaled so the
   joints both pairs triangulate lie at the same depths;
3. bundle adjustment of all poses, focal lengths and the joints of a subsample of frames, with the
   person's bone lengths held constant across frames (ten class lengths, a few millimetres of slack):
   the lengths tie the frames together and are what pins the focal lengths;
4. the metric scale from the person's height (the one thing the images cannot give).

The world of the result is view 1's camera axes (x right, y down, z forward), scaled to metres.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix
from scipy.spatial.transform import Rotation

from ..errors import InputError
from ..nanstats import nanmedian
from ..skeleton import SEGMENT_CLASS, SEGMENTS, class_lengths_from_segments, segment_lengths, standing_height
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


def _pack(cams: list[ViewCamera], points: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    parts = []
    for k, c in enumerate(cams):
        if k:
            parts += [Rotation.from_matrix(c.rotation).as_rotvec(), c.position]
        parts.append([np.log(c.focal_px)])
    return np.concatenate(parts + [points.ravel(), np.log(lengths)])


def _unpack(x: np.ndarray, cams: list[ViewCamera], n_points: int):
    out, i = [], 0
    for k, c in enumerate(cams):
        if k:
            r = Rotation.from_rotvec(x[i:i + 3]).as_matrix()
            pos = x[i + 3:i + 6]
            i += 6
        else:
            r, pos = np.eye(3), np.zeros(3)
        out.append(ViewCamera(name=c.name, image_size=c.image_size, focal_px=float(np.exp(x[i])), rotation=r,
                              position=pos))
        i += 1
    pts = x[i:i + 3 * n_points].reshape(n_points, 3)
    lengths = np.exp(x[i + 3 * n_points:])
    return out, pts, lengths


def bundle_adjust(cams: list[ViewCamera], pixels: np.ndarray, points: np.ndarray, *, slack: float = LENGTH_SLACK,
                  max_nfev: int = 60) -> tuple[list[ViewCamera], np.ndarray, np.ndarray]:
    """Refine poses (view 1 fixed), focal lengths and points (F, 17, 3) against ``pixels`` (V, F, 17, 2),
    with the 16 bones of every frame held near ten shared class lengths.  The scale is kept by
    holding view 2's distance from view 1.  Returns (cameras, points, class lengths)."""
    v, f = pixels.shape[:2]
    pts = np.where(np.isfinite(points), points, np.nanmean(points.reshape(-1, 3), axis=0))
    seg = segment_lengths(pts)
    lengths = np.nanmedian(class_lengths_from_segments(seg), axis=0)
    lengths = np.where(np.isfinite(lengths) & (lengths > 0), lengths, np.nanmedian(lengths))
    base = float(np.linalg.norm(cams[1].position))
    x0 = _pack(cams, pts.reshape(-1, 3), lengths)
    obs = np.isfinite(pixels).all(axis=-1)                                     # (V, F, 17)
    vi, fi, ji = np.nonzero(obs)
    n_pts = f * 17
    pidx = fi * 17 + ji
    par, chi = np.array([p for p, _ in SEGMENTS]), np.array([c for _, c in SEGMENTS])
    cls = np.array(SEGMENT_CLASS)
    cam_cols = []
    col = 0
    for k in range(v):
        width = 7 if k else 1
        cam_cols.append(np.arange(col, col + width))
        col += width
    p0 = col
    l0 = p0 + 3 * n_pts

    def residuals(x):
        cs, p, lens = _unpack(x, cams, n_pts)
        res = np.empty((len(vi), 2))
        for k, c in enumerate(cs):
            m = vi == k
            y = c.to_camera(p[pidx[m]])
            z = np.maximum(y[:, 2:3], 1e-3 * base)          # behind the camera costs, never hides
            res[m] = (c.focal_px * y[:, :2] / z + c.centre - pixels[k, fi[m], ji[m]]) / HUBER_PX
        pf = p.reshape(f, 17, 3)
        bone = np.linalg.norm(pf[:, chi] - pf[:, par], axis=-1)                # (F, 16)
        lres = (bone - lens[cls]) / (slack * lens[cls])
        gauge = [(np.linalg.norm(cs[1].position) - base) / (1e-3 * base)]
        return np.concatenate([np.nan_to_num(res.ravel(), nan=0.0), lres.ravel(), gauge])

    n_res = 2 * len(vi) + 16 * f + 1
    sp = lil_matrix((n_res, x0.size), dtype=np.int8)
    rows = np.arange(len(vi))
    for k in range(v):
        m = vi == k
        for c_ in cam_cols[k]:
            sp[2 * rows[m], c_] = 1
            sp[2 * rows[m] + 1, c_] = 1
    for d in range(3):
        sp[2 * rows, p0 + 3 * pidx + d] = 1
        sp[2 * rows + 1, p0 + 3 * pidx + d] = 1
    brow = 2 * len(vi) + np.arange(16 * f)
    bf = np.repeat(np.arange(f), 16)
    bs = np.tile(np.arange(16), f)
    for d in range(3):
        sp[brow, p0 + 3 * (bf * 17 + par[bs]) + d] = 1
        sp[brow, p0 + 3 * (bf * 17 + chi[bs]) + d] = 1
    sp[brow, l0 + cls[bs]] = 1
    sp[n_res - 1, cam_cols[1][3:6]] = 1
    lo, hi = np.full(x0.size, -np.inf), np.full(x0.size, np.inf)
    for k in range(v):                              # lenses stay within 1/5 to 5 times where they start
        col_f = cam_cols[k][-1]
        lo[col_f], hi[col_f] = x0[col_f] - np.log(5.0), x0[col_f] + np.log(5.0)
    fit = least_squares(residuals, x0, bounds=(lo, hi), jac_sparsity=sp.tocsr(), loss="huber", f_scale=1.0,
                        max_nfev=max_nfev,
                        method="trf", tr_solver="lsmr", x_scale="jac")
    if not np.isfinite(fit.x).all():
        return cams, pts, lengths                      # diverged: keep where it started
    try:
        cs, p, lens = _unpack(fit.x, cams, n_pts)
    except InputError:                                 # a lens run off to nothing or to infinity
        return cams, pts, lengths
    return cs, p.reshape(f, 17, 3), lens


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
    for slack in SLACK_SCHEDULE:          # loose first: a wrong lens guess bends every bone at the start
        cams, pts_sub, lengths = bundle_adjust(cams, pixels[:, sub], pts_sub, slack=slack, max_nfev=100)
    scale = height_m / float(standing_height(lengths))
    cams = [ViewCamera(c.name, c.image_size, c.focal_px, c.rotation, c.position * scale) for c in cams]
    report = {"essential_inliers": float(inliers.mean()), "bundle_frames": int(len(sub)),
              "class_lengths_m": (lengths * scale).tolist(), "focal_guess_px": guess}
    return cams, report


__all__ = ["BUNDLE_FRAMES", "bundle_adjust", "calibrate_from_person", "relative_pose"]
