"""Step 3 (paper 3.3): which foot is the stance foot in every frame.

The paper tests "every possible case of foot swapping" in a moving spell and keeps
the one that makes the camera motion smoothest; with swaps at least p frames
apart that is exponential in the spell length.  The cost it minimises is a sum of
per-frame terms (a foot's own misfit) and neighbouring-frame terms (how much the
camera increment changes from one frame to the next), so the same minimum is
found in linear time by dynamic programming over frames.  The state is the stance
foot plus how long it has been the stance foot (capped at the minimum stance
duration), which enforces "no lift-off within p frames of touching down".

:func:`stance_brute_force` keeps the paper's enumeration for short spells; the
tests use it to show the dynamic programme picks the same sequence.
"""

from __future__ import annotations

import numpy as np


def fill_unknown(costs: np.ndarray, default: float = 1.0) -> np.ndarray:
    """``costs`` with every unknown (non-finite) entry set to the 90th percentile of the known ones, or to
    ``default`` if none is known: a frame with a missing foot neither wins nor rules out a state."""
    known = np.isfinite(costs)
    good = costs[known]
    return np.where(known, costs, np.percentile(good, 90) if good.size else default)


def _check(unary: np.ndarray, pairwise: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    unary = np.asarray(unary, dtype=float)
    n = unary.shape[0]
    if pairwise is None:
        pairwise = np.zeros((n, 2, 2))
    pairwise = np.asarray(pairwise, dtype=float)
    if unary.shape != (n, 2) or pairwise.shape != (n, 2, 2):
        raise ValueError("unary must be (F, 2) and pairwise (F, 2, 2)")
    return unary, pairwise


def sequence_cost(states: np.ndarray, unary: np.ndarray, pairwise: np.ndarray | None = None) -> float:
    """Total cost of a stance sequence (0 = left, 1 = right).

    ``pairwise[i, a, b]`` is the cost of stance ``a`` at frame i-1 followed by
    ``b`` at frame i (row 0 unused).
    """
    unary, pairwise = _check(unary, pairwise)
    s = np.asarray(states, dtype=int)
    total = unary[np.arange(s.size), s].sum()
    if s.size > 1:
        total += pairwise[np.arange(1, s.size), s[:-1], s[1:]].sum()
    return float(total)


def valid_sequence(states: np.ndarray, min_run: int) -> bool:
    """Every stance run except the first and the last lasts at least ``min_run`` frames.

    The first run may have started before the spell and the last may continue after it.
    """
    s = np.asarray(states, dtype=int)
    cuts = np.flatnonzero(np.diff(s)) + 1
    bounds = np.concatenate([[0], cuts, [s.size]])
    lengths = np.diff(bounds)
    # A swap needs the run it ends to have lasted min_run frames (except the first run).
    return bool(np.all(lengths[1:-1] >= min_run)) if lengths.size > 2 else True


def stance_dp(unary: np.ndarray, pairwise: np.ndarray | None = None, min_run: int = 1) -> np.ndarray:
    """Minimum-cost stance sequence (F,) of 0/1 under the minimum-run constraint, in O(F * min_run)."""
    unary, pairwise = _check(unary, pairwise)
    n = unary.shape[0]
    if n == 0:
        return np.zeros(0, dtype=int)
    m = max(1, int(min_run))
    # State index: foot * m + (age - 1), age = frames in the current run, capped at m.
    n_states = 2 * m
    foot = np.repeat([0, 1], m)
    age = np.tile(np.arange(1, m + 1), 2)
    cost = np.full(n_states, np.inf)
    cost[np.array([0, 1]) * m + (m - 1)] = unary[0]   # the first run may be old already
    back = np.zeros((n, n_states), dtype=np.int32)
    stay_to = foot * m + np.minimum(age + 1, m) - 1
    for i in range(1, n):
        new = np.full(n_states, np.inf)
        arg = np.zeros(n_states, dtype=np.int32)
        # Stay on the same foot.
        c_stay = cost + pairwise[i, foot, foot]
        # Several ages map to the capped age m: keep the best.
        order = np.argsort(c_stay, kind="stable")[::-1]
        new[stay_to[order]] = c_stay[order]
        arg[stay_to[order]] = order
        # Swap: only from a run that has lasted m frames (or is the first run).
        for f in (0, 1):
            src = f * m + (m - 1)
            dst = (1 - f) * m + 0
            c_swap = cost[src] + pairwise[i, f, 1 - f]
            if c_swap < new[dst]:
                new[dst] = c_swap
                arg[dst] = src
        cost = new + unary[i][foot]
        back[i] = arg
    state = int(np.argmin(cost))
    out = np.empty(n, dtype=int)
    for i in range(n - 1, -1, -1):
        out[i] = foot[state]
        state = back[i, state]
    return out


def _swap_cases(n: int, m: int, start: int = 1):
    """Every tuple of swap frames in [start, n) whose consecutive swaps are >= m frames apart."""
    yield ()
    for c in range(start, n):
        for rest in _swap_cases(n, m, c + m):
            yield (c,) + rest


def stance_brute_force(unary: np.ndarray, pairwise: np.ndarray | None = None, min_run: int = 1,
                       max_frames: int = 200) -> np.ndarray:
    """The paper's enumeration: try every admissible set of swap frames, keep the cheapest."""
    unary, pairwise = _check(unary, pairwise)
    n = unary.shape[0]
    if n > max_frames:
        raise ValueError(f"brute force limited to {max_frames} frames, got {n}")
    m = max(1, int(min_run))
    best, best_cost = None, np.inf
    for cuts in _swap_cases(n, m):
        for first in (0, 1):
            s = np.full(n, first)
            for j, c in enumerate(cuts):
                s[c:] = first if j % 2 else 1 - first
            c = sequence_cost(s, unary, pairwise)
            if c < best_cost - 1e-12:
                best, best_cost = s, c
    return best
