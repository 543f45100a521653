"""Reading a sequence between and around its frames: the two small index rules every resampler here uses.

Why one place: the working-rate resampler, the video lifter at run time and the video lifter's training
windows all read values at fractional frame positions, and the lifter must read its windows exactly as it
was trained on them; the person's boxes and the lifter's lost frames both take the nearest frame that has
something.  Plain numpy on frame indices; nothing here knows what the values are.
"""

from __future__ import annotations

import numpy as np


def frames_between(positions: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(i0, i1, w) for fractional frame ``positions`` (any shape) clamped to ``[lo, hi]`` (scalars or
    arrays broadcast with them): the frames before and after each, and the weight of the one after, so
    that ``v[i0] * (1 - w) + v[i1] * w`` reads ``v`` linearly between frames and holds it at the ends."""
    p = np.clip(positions, lo, hi).astype(float)
    i0 = np.floor(p).astype(int)
    i1 = np.minimum(i0 + 1, hi)
    return i0, i1, p - i0


def nearest_marked(marked: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """For each of ``frames``, the index into ``marked`` (sorted frame numbers, at least one) of the nearest
    marked frame, the earlier on a tie."""
    marked = np.asarray(marked)
    after = np.clip(np.searchsorted(marked, frames), 0, marked.size - 1)
    before = np.clip(after - 1, 0, marked.size - 1)
    return np.where(np.abs(marked[before] - frames) <= np.abs(marked[after] - frames), before, after)
