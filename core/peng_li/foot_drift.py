"""Beyond the paper: the planted ankle's own creep, measured where the camera stands still.

Why: the paper tracks a rotating camera through a moving spell by treating the stance foot's
ankle as a static scene point.  A walking ankle is not static while its foot is planted: the
foot rolls over the heel, lies flat, then lifts its heel, so the ankle joint creeps forward and
rises over each stance.  Chained over the stance runs of a moving spell, that creep is read as
camera rotation, and every later frame inherits the error.  Measured on
``bandai_dataset-1_walk_normal`` (1 px, paper's method): over a 39-frame tilt spell of 3.7
degrees the camera picked up 0.72 degrees of pan and 0.65 degrees of extra tilt, which then
stayed for the rest of the clip (median error 0.97 degrees).

Where the camera is still, the same creep is visible directly: the stiller foot's image velocity.
Its mean over the still spells (film mm per frame) is subtracted from the feet before a spell's
*rotating* camera is tracked; the *zooming* model keeps the raw feet (the correction made its
focal lengths worse: median over the zoom clips unchanged, but the built-in walk 0.27 -> 0.64 %
and the kick 0.68 -> 2.04 %).  One mean for the whole clip: a window of still frames near each
spell was tried (15, 30, 45, 60, 90 frames either side) and swung single clips widely (the kick
0.25-1.84 degrees) for no steady gain.

Measured on the 15 clips (14 shared + built-in walk, 900 frames max, pan/tilt/zoom, 1 px), median
camera rotation error of the paper's pipeline without / with the correction: median over clips
0.97 -> 0.65 degrees; 10 clips better (the kick 1.99 -> 0.76, the walks 0.59-0.97 -> 0.35-0.39),
01_01 worse (10.6 -> 11.3, where the camera is lost anyway) and neutral, 131_03 a little worse
(0.33 -> 0.36, 0.69 -> 0.72); jogging and side-skip unchanged (13.9, 7.9).  Through the joint method
(``python -m core evaluate ... --method paper,joint``, same clips): median over clips 0.97 -> 0.64
degrees at 1 px, 1.05 -> 0.64 at 0 px, 1.07 -> 0.67 at 2 px, 1.04 -> 0.84 with 20 % drop-out, 1.10 ->
0.96 with all five kinds of camera motion; with rotation+zoom and roll and no still spell 3.17 ->
3.26 (its "still" spells move, so the creep measured there is wrong).  Proportions barely move (1 px
0.216 / 1.18 -> 0.221 / 1.18 pp; 2 px 0.305 / 1.31 -> 0.30 / 1.50, the kick's neck); whole-clip 3D
error 409 -> 406 mm.  It is a correction of the paper, so the paper's own setting
(:data:`core.peng_li.params.PAPER`) leaves it off; the joint method turns it on for its start.
"""

from __future__ import annotations

import numpy as np

#: Fewer usable still-camera frame pairs than this: no correction (the mean would be noise).
MIN_PAIRS = 10


def stance_ankle_drift(feet: np.ndarray, still: np.ndarray, stance: np.ndarray) -> np.ndarray:
    """Mean image velocity (2,) of the planted ankle where the camera is still, film mm per frame.

    ``feet`` (F, 2, 2) film points of the left and right ankle (NaN where missing), ``still`` (F,)
    where the camera is still, ``stance`` (F,) the stiller foot there (0 left, 1 right).  Only pairs
    of consecutive still frames with the same stance foot count (a swap is a jump, not a creep);
    zero when fewer than :data:`MIN_PAIRS` remain.
    """
    feet = np.asarray(feet, dtype=float)
    n = feet.shape[0]
    if n < 2:
        return np.zeros(2)
    still = np.asarray(still, dtype=bool)
    stance = np.asarray(stance)
    ok = still[:-1] & still[1:] & (stance[:-1] == stance[1:]) & (stance[:-1] >= 0)
    idx = np.nonzero(ok)[0]
    v = feet[idx + 1, stance[idx]] - feet[idx, stance[idx]]
    v = v[np.all(np.isfinite(v), axis=1)]
    if len(v) < MIN_PAIRS:
        return np.zeros(2)
    return v.mean(axis=0)


def without_drift(feet: np.ndarray, drift: np.ndarray) -> np.ndarray:
    """Both feet (F, 2, 2) with the creep ``drift`` (2,) per frame taken out, counted from the first frame.

    Taking the same ramp off both feet removes ``drift`` from every frame-to-frame step of
    whichever foot is planted, which is all the rotating camera model reads.
    """
    feet = np.asarray(feet, dtype=float)
    return feet - np.asarray(drift, dtype=float)[None, None, :] * np.arange(feet.shape[0])[:, None, None]
