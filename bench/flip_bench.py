"""How far Flip Bone Depth takes an animator: the motion bench's cases, each mirrored stretch flipped once.

For every case of ``bench/motion_bench.py`` (the same clips, halves, scenarios and draws) the estimate as
shipped is put right the way an animator would with *Flip Bone Depth* (``core.motion_cleanup.depth_flip``):
every stretch of consecutive frames where a limb bone is mirrored (more than 45 degrees off the truth after
the frame's alignment, :func:`core.evaluation.metrics.limb_angles_deg`) is flipped once, and the flip is
kept only if it brings that bone nearer the truth over the stretch (the animator compares it with the
footage and undoes it otherwise). Stretches shorter than ``--min-frames`` are left (too short to notice).
Printed per case and summed: frames with a mirrored limb before and after, per-frame error (P-MPJPE)
before and after, the planted ankles' speed over the truth's before and after (the flips do not hold
the feet again), the stretches flipped and those kept.

    python bench/flip_bench.py ../shared/data/bvh/*.bvh --scenario all --half report
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.motion_bench import _arrays, add_case_arguments, chosen_cases, film, motion_scores  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation import metrics  # noqa: E402
from core.motion_cleanup.depth_flip import flip_depth  # noqa: E402
from core.runs import runs  # noqa: E402
from core.skeleton import JOINTS  # noqa: E402


def stretches(mask: np.ndarray, min_frames: int) -> list[tuple[int, int]]:
    """(first, last) of each run of True in ``mask`` (F,) at least ``min_frames`` long."""
    return [(int(a), int(b) - 1) for a, b in runs(mask) if b - a >= min_frames]


def hand_flips(est, truth, min_frames: int):
    """(the estimate after an animator's flips, stretches tried, stretches kept)."""
    tried = kept = 0
    for b, (_, child) in enumerate(metrics.LIMB_BONES):
        angles = metrics.limb_angles_deg(_arrays(est)[0], truth.joints_3d)[:, b]
        for first, last in stretches(angles > metrics.MIRROR_ANGLE_DEG, min_frames):
            tried += 1
            fixed, _ = flip_depth(est, JOINTS[child], first, last)
            after = metrics.limb_angles_deg(_arrays(fixed)[0][first:last + 1], truth.joints_3d[first:last + 1])[:, b]
            if after.mean() < angles[first:last + 1].mean():
                est, kept = fixed, kept + 1
    return est, tried, kept


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_case_arguments(ap, scenario="all")
    ap.add_argument("--min-frames", type=int, default=3, help="the shortest stretch an animator flips (frames)")
    args = ap.parse_args(argv)
    scen, chosen = chosen_cases(ap, args)
    rows = []
    for c in chosen:
        tracks, truth = film(c, args.max_s)
        est = estimate(tracks, "joint")
        fixed, tried, kept = hand_flips(est, truth, args.min_frames)
        before, after = _arrays(est)[0], _arrays(fixed)[0]
        feet = [motion_scores(*_arrays(e), tracks, truth)["planted_excess_mm_s"] for e in (est, fixed)]
        r = {"scenario": c["scenario"], "clip": os.path.basename(c["clip"]), "feet": feet[0], "feet_after": feet[1],
             "mirrored": metrics.mirrored_limb_pct(before, truth.joints_3d),
             "mirrored_after": metrics.mirrored_limb_pct(after, truth.joints_3d),
             "mm": metrics.mpjpe_per_frame_m(before, truth.joints_3d) * 1000.0,
             "mm_after": metrics.mpjpe_per_frame_m(after, truth.joints_3d) * 1000.0, "tried": tried, "kept": kept}
        rows.append(r)
        print(f"{r['clip'][:34]:<34} {r['scenario']:<10} mirrored {r['mirrored']:5.1f} -> {r['mirrored_after']:5.1f} % "
              f"P-MPJPE {r['mm']:5.1f} -> {r['mm_after']:5.1f} mm, planted excess {r['feet']:4.0f} -> "
              f"{r['feet_after']:4.0f} mm/s, stretches flipped {tried}, kept {kept}", flush=True)
    print(f"\n| scenario ({args.half} half) | cases | mirrored frames %, mean before -> after | per-frame error mm, "
          "mean before -> after | planted excess mm/s, median case before -> after | stretches flipped (kept) |")
    print("|---|---|---|---|---|---|")
    for s in scen:
        rs = [r for r in rows if r["scenario"] == s]
        if rs:
            print(f"| {s} | {len(rs)} | {np.mean([r['mirrored'] for r in rs]):.1f} -> "
                  f"{np.mean([r['mirrored_after'] for r in rs]):.1f} | {np.mean([r['mm'] for r in rs]):.1f} -> "
                  f"{np.mean([r['mm_after'] for r in rs]):.1f} | {np.nanmedian([r['feet'] for r in rs]):.0f} -> "
                  f"{np.nanmedian([r['feet_after'] for r in rs]):.0f} | {sum(r['tried'] for r in rs)} "
                  f"({sum(r['kept'] for r in rs)}) |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
