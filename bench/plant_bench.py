"""How far Plant Foot takes an animator: the motion bench's cases, each sliding contact planted once.

For every case of ``bench/motion_bench.py`` (the same clips, halves, scenarios and draws) the estimate as
shipped is put right the way an animator would with *Plant Foot* (``core.motion_cleanup.foot_plant``):
every stretch of at least ``--min-s`` seconds where the true ankle stands (the bench's own measure of a
planted ankle) and the estimate's ankle strays ``--slide-m`` or more from its median place over the
stretch is planted once, and undone where the tool warns that the place lies beyond the leg's reach (the
body moved away from it over the stretch: the animator sees the leg pulled straight). The animator judges the
stretches from the footage; this one is handed them from the truth, so it is the best an animator's clicks
can do with the tool, not what a hurried one will.
Printed per case and summed: the planted ankles' speed over the truth's (mean over the ankle-frames where
the true ankle stands) before and after, per-frame error (P-MPJPE), frames with a mirrored limb, and the
stretches planted.

    python bench/plant_bench.py ../shared/data/bvh/*.bvh --scenario all --half report
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.motion_bench import (  # noqa: E402
    PLANTED_TRUE_MAX_M_S,
    _arrays,
    add_case_arguments,
    chosen_cases,
    film,
    motion_scores,
)
from core.errors import InputError  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation import metrics  # noqa: E402
from core.motion_cleanup.foot_plant import REACH_WARN_M, plant_foot, stance_span  # noqa: E402
from core.runs import runs  # noqa: E402
from core.skeleton import FEET  # noqa: E402


def hand_plants(est, truth, min_s: float, slide_m: float, offered: bool = False):
    """(the estimate after an animator's plants, stretches planted); ``offered``: each plant over the frames the
    tool offers at the contact's middle frame (:func:`core.motion_cleanup.foot_plant.stance_span`) instead of the
    contact's own, none where it offers nothing."""
    planted = metrics.planted_from_stance(truth.stance, truth.n_frames) & metrics.planted_from_speed(
        truth.joints_3d, truth.fps, PLANTED_TRUE_MAX_M_S)
    count = 0
    for s, foot in enumerate("lr"):
        for a, b in runs(planted[:, s]):
            first, last = int(a), int(b) - 1
            if b - a < min_s * truth.fps:
                continue
            ankle = _arrays(est)[0][first:last + 1, FEET[foot]]
            if np.max(np.linalg.norm(ankle - np.median(ankle, axis=0), axis=1)) < slide_m:
                continue
            if offered:
                try:
                    first, last = stance_span(est, foot, (first + last) // 2)
                except InputError:
                    continue
            planted_est, report = plant_foot(est, foot, first, last)
            if report["unreached_m"] <= REACH_WARN_M:           # the tool warns of a leg pulled straight: undone
                est, count = planted_est, count + 1
    return est, count


def _within(values) -> int:
    """How many cases' planted ankles are within 30 mm/s of the truth's speed (the target's measure)."""
    return int(sum(abs(v) <= 30 for v in values))


def _change(rows, stat, key: str, digits: int) -> str:
    """``stat`` over the cases of ``key`` before and after the plants, as 'before -> after'."""
    return f"{stat([r[key] for r in rows]):.{digits}f} -> {stat([r[key + '_after'] for r in rows]):.{digits}f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_case_arguments(ap, scenario="all")
    ap.add_argument("--min-s", type=float, default=0.1, help="the shortest contact an animator plants (seconds)")
    ap.add_argument("--slide-m", type=float, default=0.02,
                    help="the least slide an animator notices (metres from the contact's median place)")
    ap.add_argument("--offered", action="store_true",
                    help="plant the frames the tool offers at each contact's middle frame, not the contact's own")
    args = ap.parse_args(argv)
    scen, chosen = chosen_cases(ap, args)
    rows = []
    for c in chosen:
        tracks, truth = film(c, args.max_s)
        est = estimate(tracks, "joint")
        fixed, count = hand_plants(est, truth, args.min_s, args.slide_m, args.offered)
        sc = [motion_scores(*_arrays(e), tracks, truth) for e in (est, fixed)]
        r = {"scenario": c["scenario"], "clip": os.path.basename(c["clip"]), "planted": count,
             **{f"{k}{tag}": s[k] for s, tag in zip(sc, ("", "_after"))
                for k in ("planted_excess_mm_s", "mpjpe_frame_mm", "mirrored_pct")}}
        rows.append(r)
        print(f"{r['clip'][:34]:<34} {r['scenario']:<10} planted excess {r['planted_excess_mm_s']:5.0f} -> "
              f"{r['planted_excess_mm_s_after']:5.0f} mm/s, P-MPJPE {r['mpjpe_frame_mm']:5.1f} -> "
              f"{r['mpjpe_frame_mm_after']:5.1f} mm, mirrored {r['mirrored_pct']:5.1f} -> "
              f"{r['mirrored_pct_after']:5.1f} %, stretches planted {count}", flush=True)
    print(f"\n| scenario ({args.half} half) | cases | planted excess mm/s, median case before -> after | mean case "
          "| cases within 30 mm/s | per-frame error mm, mean | mirrored frames %, mean | stretches planted |")
    print("|---|---|---|---|---|---|---|---|")
    for s in scen:
        rs = [r for r in rows if r["scenario"] == s]
        if rs:
            print(f"| {s} | {len(rs)} | {_change(rs, np.nanmedian, 'planted_excess_mm_s', 0)} "
                  f"| {_change(rs, np.nanmean, 'planted_excess_mm_s', 0)} "
                  f"| {_change(rs, _within, 'planted_excess_mm_s', 0)} | {_change(rs, np.mean, 'mpjpe_frame_mm', 1)} "
                  f"| {_change(rs, np.mean, 'mirrored_pct', 1)} | {sum(r['planted'] for r in rs)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
