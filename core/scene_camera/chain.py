"""A starting camera for the bundle adjustment, chained from frame to frame.

Between consecutive usable frames the shared points give the zoom (the ratio of their spreads
about their centroid) and then the rotation (Kabsch on their viewing rays, each frame with its
own focal length).  Small steps, so the chain starts the adjustment close even when the camera
turns by tens of degrees over the clip; the absolute focal length is the caller's guess, which
the adjustment then corrects where the turn determines it.
"""

from __future__ import annotations

import numpy as np

from .bundle import BundleState, Observations


def rays(uv: np.ndarray, f: float) -> np.ndarray:
    r = np.concatenate([uv, np.full((uv.shape[0], 1), f)], axis=1)
    return r / np.linalg.norm(r, axis=1, keepdims=True)


def kabsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation R minimising sum |R a_k - b_k|^2 (rows are vectors)."""
    u, _, vt = np.linalg.svd(b.T @ a)
    dfix = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, dfix]) @ vt


def chained_start(obs: Observations, uv_by_frame: list[dict], f0_px: float, ref: int) -> BundleState:
    """Rotations and log focal lengths of every frame and the points' directions (frame-``ref`` axes).

    ``uv_by_frame[i]`` maps point index -> (2,) pixels from the centre for frame ``i``.
    """
    F, S = obs.n_frames, obs.n_points
    R = np.repeat(np.eye(3)[None], F, axis=0)
    g = np.full(F, np.log(f0_px))
    for direction in (range(ref + 1, F), range(ref - 1, -1, -1)):
        for i in direction:
            k = i - 1 if i > ref else i + 1
            common = sorted(set(uv_by_frame[i]) & set(uv_by_frame[k]))
            R[i], g[i] = R[k], g[k]
            if len(common) < 2:
                continue
            a = np.array([uv_by_frame[k][s] for s in common])
            b = np.array([uv_by_frame[i][s] for s in common])
            spread_a = np.sqrt(np.mean(np.sum((a - a.mean(0)) ** 2, axis=1)))
            spread_b = np.sqrt(np.mean(np.sum((b - b.mean(0)) ** 2, axis=1)))
            if spread_a > 1.0 and spread_b > 1.0:
                g[i] = g[k] + np.log(spread_b / spread_a)
            step = kabsch(rays(a, np.exp(g[k])), rays(b, np.exp(g[i])))
            R[i] = step @ R[k]
    d = np.zeros((S, 3))
    for i in range(F):
        for s, p in uv_by_frame[i].items():
            d[s] += R[i].T @ rays(np.asarray(p)[None], np.exp(g[i]))[0]
    n = np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where(n > 0, d / np.maximum(n, 1e-12), np.array([0.0, 0.0, 1.0]))
    return BundleState(R, g, d)
