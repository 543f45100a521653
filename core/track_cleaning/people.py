"""Where the tracks leave one person for another.

A detector that follows one person can slide onto someone else when two
people cross, or re-detect a different person after losing the first (real
footage: docs/pose_detection.md).  One estimate assumes one body, so such a
jump has to be said.

Each joint of a real person moves smoothly: its deviation from the
constant-velocity guess of the two frames before is small at video rates,
even running.  A frame is a switch when, as the median over the joints seen
in all frames concerned (so one or two wrong joints do not count; left and
right are matched either way round, so a detector's left/right exchange does
not either), the jump, the deviation from that guess, and the
distance from the old path :data:`HOLD_FRAMES` frames later all exceed
:data:`SWITCH_SIZES` body sizes (the median 2D segment length, the larger of
the two frames').  A detector's gross outlier (1-3 frames) comes back to the
old path, and its end lands where the path before it leads; someone else
does neither.  Run it on the raw tracks: a cleaning that
rejects the jumped frames as outliers hides it.
"""

from __future__ import annotations

import numpy as np

from ..nanstats import nanmedian
from ..runs import runs
from ..skeleton import MIRROR
from .body_scale import segment_lengths_2d

SWITCH_SIZES = 2.0
HOLD_FRAMES = 4
_MIRROR = list(MIRROR)


def _distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 17) joint distances between poses, each left/right pair matched either way round."""
    direct = np.linalg.norm(a - b, axis=-1)
    crossed = np.linalg.norm(a - b[..., _MIRROR, :], axis=-1)
    pair_direct = direct + direct[..., _MIRROR]
    pair_crossed = crossed + crossed[..., _MIRROR]
    return np.where(pair_crossed < pair_direct, crossed, direct)


def _median_distance(a: np.ndarray, b: np.ndarray) -> float:
    d = _distances(a, b)
    d = d[np.isfinite(d)]
    return float(np.median(d)) if d.size >= 3 else float("nan")


def person_switches(xy: np.ndarray) -> np.ndarray:
    """Frame indices (sorted) at which the (F, 17, 2) tracks jump to another person."""
    with np.errstate(invalid="ignore", over="ignore"):     # a joint at 1e300 px: an outlier, not an error
        return _switches(xy)


def longest_one_person_stretch(switches, found) -> tuple[int, int]:
    """(start, end_exclusive) of the longest run of frames where the (F,) mask ``found`` holds and no switch
    of :func:`person_switches` falls inside (a switch frame is the next person's first); (0, 0) if none.
    The advice "estimate one person's stretch" (self-check) and the detection report both use it."""
    cuts = np.asarray(switches, dtype=int)
    pieces = []
    for a, b in runs(found):
        inner = cuts[(cuts > a) & (cuts < b)].tolist()
        pieces += list(zip([a, *inner], [*inner, b]))
    a, b = max(pieces, key=lambda r: r[1] - r[0], default=(0, 0))
    return int(a), int(b)


def _switches(xy: np.ndarray) -> np.ndarray:
    xy = np.asarray(xy, dtype=float)
    n = xy.shape[0]
    if n < 3:
        return np.zeros(0, dtype=int)
    size = nanmedian(segment_lengths_2d(xy), axis=1)
    jump = nanmedian(_distances(xy[2:], xy[1:-1]), axis=1)
    candidates = np.flatnonzero(jump > SWITCH_SIZES * np.fmax(size[2:], size[1:-1])) + 2
    out = []
    for t in candidates:
        unit = float(np.fmax(size[t], size[t - 1]))
        velocity = xy[t - 1] - xy[t - 2]
        if not _median_distance(xy[t], xy[t - 1] + velocity) > SWITCH_SIZES * unit:
            continue
        later = min(n - 1, t + HOLD_FRAMES)
        apart = _median_distance(xy[later], xy[t - 1] + (later - t + 1) * velocity)
        if not (later > t and apart > SWITCH_SIZES * unit):     # NaN (nothing seen then) is no evidence
            continue
        # the end of a glitch lands back on the path from before it
        back = [_median_distance(xy[t], xy[t - k] + k * (xy[t - k] - xy[t - k - 1]))
                for k in range(2, min(HOLD_FRAMES + 1, t - 1) + 1)]
        if not any(b <= SWITCH_SIZES * unit for b in back):
            out.append(int(t))
    return np.array(out, dtype=int)
