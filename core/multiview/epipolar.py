"""Two-view epipolar geometry of point pairs: the normalised eight-point fit and the Sampson distance.

Shared by the calibration (essential matrices of normalised image points, :mod:`.calibrate`) and the
synchronisation (fundamental matrices of pixels, :mod:`.sync`).  Pairs satisfy ``b^T M a = 0``.
"""

from __future__ import annotations

import numpy as np


def _normalise(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points moved to their centroid and scaled to a mean distance of sqrt(2) (Hartley), and the 3x3
    transform that did it."""
    c = points.mean(axis=0)
    s = np.sqrt(2) / max(float(np.mean(np.linalg.norm(points - c, axis=1))), 1e-12)
    return (points - c) * s, np.array([[s, 0, -s * c[0]], [0, s, -s * c[1]], [0, 0, 1.0]])


def _linear_fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M in normalised coordinates, the transform of a, that of b): the least-squares solution of
    ``b^T M a = 0`` over pairs (N >= 8, 2)."""
    an, ta = _normalise(a)
    bn, tb = _normalise(b)
    m = np.einsum("ni,nj->nij", np.c_[bn, np.ones(len(bn))], np.c_[an, np.ones(len(an))]).reshape(len(a), 9)
    # the null vector is V's ninth row: full matrices for the 8 points of a RANSAC sample, reduced ones
    # for many points (a full U would be N x N)
    return np.linalg.svd(m, full_matrices=len(m) < 9)[2][-1].reshape(3, 3), ta, tb


def fundamental(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Fundamental matrix (rank 2) from pixel pairs (N >= 8, 2)."""
    f, ta, tb = _linear_fit(a, b)
    u, s, vt = np.linalg.svd(f)
    return tb.T @ (u @ np.diag([s[0], s[1], 0.0]) @ vt) @ ta


def essential(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Essential matrix (two equal singular values, one zero) from normalised image pairs (N >= 8, 2)."""
    e, ta, tb = _linear_fit(a, b)
    u, _, vt = np.linalg.svd(tb.T @ e @ ta)
    return u @ np.diag([1.0, 1.0, 0.0]) @ vt


def sampson(m: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """First-order geometric (Sampson) distance of each pair to ``b^T M a = 0``, in the pairs' units."""
    x1 = np.c_[a, np.ones(len(a))]
    x2 = np.c_[b, np.ones(len(b))]
    mx1 = x1 @ m.T
    mtx2 = x2 @ m
    num = np.sum(x2 * mx1, axis=1) ** 2
    return np.sqrt(num / (mx1[:, 0] ** 2 + mx1[:, 1] ** 2 + mtx2[:, 0] ** 2 + mtx2[:, 1] ** 2 + 1e-30))
