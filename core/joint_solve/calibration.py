"""Focal self-calibration, and an honest "cannot tell" when the data do not fix it.

Why the focal length is observable at all: the camera turns about a fixed
point, so planted feet (static points) move in the image as a pure rotation,
whose image motion depends on ``f``; and a rigid figure of known length ratios
seen in many poses shows perspective foreshortening (near parts larger) that
a wrong ``f`` cannot reproduce.  Both fade when the person is far away and
the camera hardly turns (weak perspective): then every ``f`` explains the
images equally well.

Method: on a chunk of the clip, run the initialisation and a short joint
solve with the focal length held (strong prior) at each value of a
logarithmic grid; the final costs form a curve over ``log f``.  Its minimum
(refined by a parabola through the three lowest neighbours) starts the full
solve, which then frees ``f``.  If the curve rises by less than
:data:`FLAT_DELTA` cost units (half a chi-square) within a factor of
:data:`FLAT_RATIO` either side of the minimum, the focal length is reported
as *not determined* with a warning, and kept as a prior in the final solve.
A user's hint skips the grid and enters the final solve as a prior.

Status: the curve is computed only on request (``with_curve``) and is not trusted: its minimum was
wrong on 3 of 4 synthetic test clips, so with no hint the 50 mm default is assumed, reported as
``focal_determined: false`` with a warning.  Since the pose lifter's directions joined the solve
(``pipeline.SOLVE_CUE_SIGMA``) a curve of whole solves leans short: held at 0.5-2 times the true focal
length, the final cost was lowest at 0.5-0.85 times it on 10 still-camera cases, at 0.5-1.0 times it with
that term off (``docs/motion.md``, where the remaining error is): the lifter's slants, shrunk towards the
picture's plane, favour a closer figure.

Measured with everything else from the truth (camera rotations, zoom ratios, stance; 300
frames, 1 px; a 12-iteration solve per focal value, lengths free): the final cost over focal / true
focal of 0.70, 0.85, 1.00, 1.18, 1.40 is lowest at 1.18 on the built-in walk and on ``walk_normal``
(1.00 costs 27 and 56 more), at 1.00 and 1.18 alike on jogging, and at 1.00 on the kick.  So even
with a perfect camera the objective places the focal length only within about 10-20 % (a parabola
through the lowest three puts it near 1.1 on three of the four clips), not within 3 %:
the person is too far away for the perspective to say more at 1 px of noise.

Closer cameras do not rescue it (measured with ``bench/ceiling.py``'s oracle: true stance, camera
rotations, lengths and poses as the start, no camera prior, focal held by a 1e-4 prior at each factor,
30 iterations; 300 frames, 1 px, true focal 20 mm so the camera stands close): the cost above its
minimum at focal / true focal 0.8, 0.9, 0.95, 1.0, 1.05, 1.1, 1.25 was, on the kick (person 2.1 m away)
80, 38, 40, 36, 57, 0, 19; on ``131_01`` (3.4 m) 253, 2, 51, 0, 56, 1, 183; on the built-in walk (9.8 m)
3432, 305, 64, 22, 0, 47, 483; on ``walk_normal`` (8.3 m) 2141, 581, 298, 164, 75, 62, 0.  Bumpy near
the truth and lowest 5-25 % off it.  At 0 px the minimum lies at 1.0 on the built-in walk (a procedural
figure that fits the model exactly), 0.95 on the kick and 1.1 on ``walk_normal``: where the
motion-capture body departs from the model (ankles creep while planted) the other terms shift it, and
noise adds the bumps.
And this module's own curve (90-frame chunk, 6 iterations per grid value, the paper's camera) put the
minimum at 0.30-2.82 times the true focal over the same four clips at 20, 35, 50 and 85 mm, calling it
clear on four of the sixteen (at 1.66, 1.15, 0.73 and 0.30 times the truth).

Also tried and not used: a stride estimate.  A planted ankle's depth is fixed, so over a stance the
pelvis' depth change read from its image scale (proportional to ``f``) must equal the change of the
ankle's depth offset in the pose (independent of ``f``); a regression over the stances gives ``f``.
With the *true* depth offsets it came out 20 % low on the walks and meaningless on jogging (stance
labels wrong); with ours it was meaningless everywhere (35 / 50 / 85 mm cameras, 1 px).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..camera import DEFAULT_FOCAL_MM, mm_per_pixel
from . import solver as slv

GRID_MM = tuple(float(v) for v in np.geomspace(15.0, 240.0, 9))
CHUNK_FRAMES = 90
GRID_ITER = 6
FLAT_RATIO = 1.5
FLAT_DELTA = 20.0


@dataclass
class Calibration:
    focal_mm: float
    determined: bool
    curve: list = field(default_factory=list)      # [[f_mm, cost], ...]
    warnings: list = field(default_factory=list)


def focal_cost_curve(film, xy_filled, stance, lengths, ratio, *, tracks, height_m, initial_state, grid=GRID_MM,
                     tick=None):
    """Cost of the chunk's joint solve with the focal length held at each grid value.

    ``initial_state`` is the joint solve's starting point (:func:`core.joint_solve.pipeline.initial_state`),
    passed in because the pipeline imports this module: the start is the pipeline's to define.
    """
    n = min(film.shape[0], CHUNK_FRAMES)
    costs = []
    for k, f in enumerate(grid):
        if tick is not None:
            tick(0.05 + 0.25 * k / len(grid), f"focal length: trying {f:.0f} mm")
        prob = slv.Problem(film=film[:n], mm_per_px=mm_per_pixel(tracks.image_size), fps=tracks.fps,
                           height_m=height_m, stance=stance[:n], focal_prior_mm=f, focal_prior_sigma=1e-4)
        x0 = initial_state(xy_filled[:n], stance[:n], f * ratio[:n], lengths, tracks.image_size, fps=tracks.fps)
        _, rep = slv.solve(prob, x0, max_iter=GRID_ITER,
                           should_cancel=None if tick is None else tick.should_cancel)
        costs.append(rep.cost)
    return np.array(costs)


def pick_minimum(grid, costs) -> tuple[float, bool]:
    """Focal at the curve's minimum (parabola in log f) and whether the curve really determines it.

    Determined means: the minimum is inside the grid, the cost rises by more
    than :data:`FLAT_DELTA` at a factor :data:`FLAT_RATIO` on *both* sides, and
    it keeps rising (no second dip) away from the minimum.  Anything else –
    a minimum at the grid's edge, a flat or bumpy curve – is "not determined":
    short solves from different starting points then disagree more than the
    data discriminate, and the honest answer is "we cannot tell".
    """
    lg = np.log(np.asarray(grid))
    costs = np.asarray(costs, dtype=float)
    k = int(np.argmin(costs))
    best = lg[k]
    if not (0 < k < len(lg) - 1) or not np.all(np.isfinite(costs)):
        return float(np.exp(best)), False
    a, b, _ = np.polyfit(lg[k - 1:k + 2], costs[k - 1:k + 2], 2)
    if a > 0:
        best = float(np.clip(-b / (2 * a), lg[k - 1], lg[k + 1]))
    left = costs[:k][::-1]          # walking away from the minimum
    right = costs[k + 1:]
    monotone = bool(np.all(np.diff(left) > 0) and np.all(np.diff(right) > 0))
    far_left = lg[:k][::-1] <= best - np.log(FLAT_RATIO)
    far_right = lg[k + 1:] >= best + np.log(FLAT_RATIO)
    rise_left = (left[far_left].max() - costs[k]) if far_left.any() else 0.0
    rise_right = (right[far_right].max() - costs[k]) if far_right.any() else 0.0
    determined = monotone and min(rise_left, rise_right) > FLAT_DELTA
    return float(np.exp(best)), bool(determined)


def self_calibrate(film, xy_filled, stance, lengths, ratio, *, tracks, height_m, focal_hint=None,
                   tick=None, with_curve: bool = False, initial_state=None) -> Calibration:
    """Focal length of frame 0: the user's hint, else the default with an honest warning (module docstring).

    ``with_curve`` also computes the focal cost curve, which needs the pipeline's ``initial_state``.
    """
    if focal_hint is not None:
        return Calibration(focal_mm=float(focal_hint), determined=True, warnings=[])
    curve, f, determined = [], DEFAULT_FOCAL_MM, False
    if with_curve:
        costs = focal_cost_curve(film, xy_filled, stance, lengths, ratio, tracks=tracks, height_m=height_m,
                                 initial_state=initial_state, tick=tick)
        curve = [[round(g, 2), round(float(c), 3)] for g, c in zip(GRID_MM, costs)]
        f_curve, ok = pick_minimum(GRID_MM, costs)
        curve.append({"minimum_mm": round(f_curve, 2), "clear_minimum": ok, "trusted": False})
    warnings = [f"focal length not determined: self-calibration is not reliable yet, assumed {f:.0f} mm "
                "(the paper's default) - give --focal-mm if you know it"]
    return Calibration(focal_mm=f, determined=determined, curve=curve, warnings=warnings)
