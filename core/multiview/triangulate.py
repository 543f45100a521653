"""Joints in 3D from their pixels in several calibrated views.

Linear triangulation (each view's two rows of ``x P X = 0``, every view weighted alike in pixels) of
every joint in every frame seen by at least two views.  With three views or more a view whose pixel
lies far from where the others put the point (a detector's outlier or a left/right exchange in that
view alone) is dropped and the point triangulated again from the rest.
"""

from __future__ import annotations

import numpy as np

from .cameras import ViewCamera

#: With three views or more, the view that fits a point worst is suspect above this many pixels ...
RESIDUAL_PX = 4.0
#: ... and dropped when the point the other views make lies further than this from its pixel.
OUTLIER_PX = 12.0


def _solve(rows: np.ndarray) -> np.ndarray:
    """Least-squares homogeneous solutions of stacked rows (..., 2V, 4) -> (..., 3); NaN if degenerate."""
    _, _, vt = np.linalg.svd(rows)
    h = vt[..., -1, :]
    with np.errstate(all="ignore"):
        x = h[..., :3] / h[..., 3:4]
    return np.where(np.abs(h[..., 3:4]) > 1e-12, x, np.nan)


def _linear(pixels: np.ndarray, cameras: list[ViewCamera], used: np.ndarray) -> np.ndarray:
    """Linear triangulation of every (frame, joint) from the views ``used`` (V, F, J) marks."""
    v = len(cameras)
    f, j = pixels.shape[1:3]
    rows = np.zeros((f, j, 2 * v, 4))
    for k, cam in enumerate(cameras):
        mat = cam.projection_matrix() / cam.focal_px          # views weigh alike in pixels
        u = np.nan_to_num(pixels[k, ..., 0])[..., None]
        w = np.nan_to_num(pixels[k, ..., 1])[..., None]
        on = used[k][..., None]
        rows[..., 2 * k, :] = np.where(on, u * mat[2] - mat[0], 0.0)
        rows[..., 2 * k + 1, :] = np.where(on, w * mat[2] - mat[1], 0.0)
    enough = used.sum(axis=0) >= 2
    return np.where(enough[..., None], _solve(rows), np.nan)


def triangulate(pixels: np.ndarray, cameras: list[ViewCamera], *, robust: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(points (F, J, 3) world, used (V, F, J) bool) from ``pixels`` (V, F, J, 2), NaN where unseen.

    Points seen by fewer than two views are NaN.  ``robust`` (three views or more): the view that fits
    a point worst (over :data:`RESIDUAL_PX`) is checked against where the other views put the point
    and dropped if that is over :data:`OUTLIER_PX` from its pixel (repeated while three views remain)."""
    pixels = np.asarray(pixels, dtype=float)
    v = pixels.shape[0]
    used = np.isfinite(pixels).all(axis=-1)                                   # (V, F, J)
    points = _linear(pixels, cameras, used)
    if not robust or v < 3:
        return points, used
    for _ in range(v - 2):
        fit = np.where(used, reprojection_errors(points, pixels, cameras), -1.0)
        worst = np.argmax(np.nan_to_num(fit, nan=-1.0), axis=0)                  # (F, J)
        worst_fit = np.take_along_axis(fit, worst[None], axis=0)[0]
        suspect = (worst_fit > RESIDUAL_PX) & (used.sum(axis=0) >= 3)
        if not suspect.any():
            break
        off = np.full(worst.shape, -1.0)
        for k, cam in enumerate(cameras):
            mine = suspect & (worst == k)
            if not mine.any():
                continue
            others = used.copy()
            others[k] = False
            err = np.linalg.norm(cam.project(_linear(pixels, cameras, others)) - pixels[k], axis=-1)
            off = np.where(mine & np.isfinite(err), err, off)
        drop = off > OUTLIER_PX
        if not drop.any():
            break
        ff, jj = np.nonzero(drop)
        used[worst[ff, jj], ff, jj] = False
        points = _linear(pixels, cameras, used)
    return points, used


def reprojection_errors(points: np.ndarray, pixels: np.ndarray, cameras: list[ViewCamera]) -> np.ndarray:
    """(V, F, J) pixel distance between each view's observation and the point's projection (NaN where unseen)."""
    return np.stack([np.linalg.norm(c.project(points) - pixels[k], axis=-1) for k, c in enumerate(cameras)])
