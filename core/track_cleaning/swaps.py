"""Left/right exchanges: a detector that swaps the legs while they cross, or the whole figure.

For each pair of limbs (legs: hip, knee, ankle; arms: shoulder, elbow, wrist) a Viterbi search over
the clip picks, per frame, how many joints from the limb's end are exchanged: none, the last one,
the last two, or the whole limb (both pairs exchanged is the whole body).  The cost of a labelling
is how far each joint jumps from one frame to the next (relative to the figure's image size,
capped so that one gross outlier cannot decide it) plus a price per second of exchanged frames, so
an exchange is undone only where continuity asks for it clearly.  The price is per second and the
jumps are per event, so the decision does not depend on the frame rate.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import LIMB_PAIRS


def _state_positions(xy: np.ndarray, left, right, depth: int) -> np.ndarray:
    """(F, 6, 2) positions of the pair's joints (left limb, then right) with the last ``depth`` exchanged."""
    left, right = list(left), list(right)
    k = len(left) - depth
    new_left = left[:k] + right[k:]
    new_right = right[:k] + left[k:]
    return xy[:, new_left + new_right]


def swap_states(xy: np.ndarray, scale: np.ndarray, fps: float, pair: str, *, price_per_s: float,
                cap: float) -> np.ndarray:
    """(F,) int: per frame, how many joints from the end of the ``pair``'s limbs are exchanged."""
    left, right = LIMB_PAIRS[pair]
    n = xy.shape[0]
    depths = len(left) + 1
    pos = np.stack([_state_positions(xy, left, right, d) for d in range(depths)])   # (S, F, 6, 2)
    if n < 2:
        return np.zeros(n, dtype=int)
    inv2 = 1.0 / np.maximum(scale[1:], 1e-9) ** 2
    # trans[a, b, t-1]: cost of state a at t-1 then b at t
    trans = np.empty((depths, depths, n - 1))
    for a in range(depths):
        d = pos[:, 1:] - pos[a, :-1][None]                         # (S, F-1, 6, 2)
        u = np.sum(d * d, axis=-1) * inv2[None, :, None]
        u = np.where(np.isfinite(u), np.minimum(u, cap), 0.0)
        trans[a] = u.sum(axis=-1)
    unary = np.array([0.0] + [price_per_s / fps] * (depths - 1))
    acc = unary.copy()
    back = np.empty((n - 1, depths), dtype=np.int8)
    for t in range(n - 1):
        total = acc[:, None] + trans[:, :, t]                       # (a, b)
        back[t] = np.argmin(total, axis=0)
        acc = total.min(axis=0) + unary
    states = np.empty(n, dtype=int)
    states[-1] = int(np.argmin(acc))
    for t in range(n - 2, -1, -1):
        states[t] = back[t, states[t + 1]]
    return states


def apply_swaps(xy: np.ndarray, conf: np.ndarray, states: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Undo the exchanges ``states`` describes; returns new (xy, conf)."""
    xy = xy.copy()
    conf = conf.copy()
    for pair, depth in states.items():
        left, right = LIMB_PAIRS[pair]
        for d in range(1, len(left) + 1):
            frames = np.flatnonzero(depth == d)
            if frames.size == 0:
                continue
            lj, rj = list(left[len(left) - d:]), list(right[len(right) - d:])
            fl, fr = np.ix_(frames, lj), np.ix_(frames, rj)
            xy[fl], xy[fr] = xy[fr].copy(), xy[fl].copy()
            conf[fl], conf[fr] = conf[fr].copy(), conf[fl].copy()
    return xy, conf
