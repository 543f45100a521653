"""The joint solve's 3D motion with and without the pose prior: per-frame error and mirrored limbs.

Each clip (the shared evaluation clips and the built-in walk and run; split into tune / report
halves as in ``bench/robust_bench.py``) is filmed once per schedule, 30 fps, a lens drawn from
18-85 mm and a view drawn per clip:

* ``moving``: the paper's camera schedule (pan, tilt, zoom), ``--noise`` px (default 1);
* ``still``: a camera standing still, 0 px.

and estimated by the joint method with the prior (:data:`core.joint_solve.pipeline.USE_POSE_PRIOR`)
and without.  Per clip and overall: P-MPJPE per frame (mean, after a similarity alignment of each
frame) and the share of frames with a mirrored limb (:func:`core.motion_prior.evaluation.frame_errors`).

    python bench/prior_joint_bench.py ../shared/data/bvh/*.bvh [--half tune] [--frames 300] [--weight 1]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.model_options import add_model_arguments, apply_model_arguments  # noqa: E402
from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.joint_solve import pipeline, signs_dp  # noqa: E402
from core.motion_prior.evaluation import frame_errors  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402

SCHEDULES = {"moving": (("pan", "tilt", "zoom"), None), "still": ((), 0.0)}


def run_case(clip: str, schedule: str, frames: int, noise: float, use_prior: bool) -> dict:
    rng = _case_rng(clip, f"prior-{schedule}", 0)
    focal = float(np.exp(rng.uniform(np.log(18.0), np.log(85.0))))
    view = float(rng.uniform(-90.0, 90.0))
    seed = int(rng.integers(1 << 30))
    kinds, fixed_noise = SCHEDULES[schedule]
    motion = load_motion(clip, fps=30.0, max_frames=frames)
    tracks, truth = synthesize(motion, kinds=kinds, focal_mm=focal, noise_px=noise if fixed_noise is None
                               else fixed_noise, seed=seed, view_offset_deg=view)
    pipeline.USE_POSE_PRIOR = use_prior
    t0 = time.perf_counter()
    est = estimate(tracks, "joint")
    sec = time.perf_counter() - t0
    j3 = np.array([f.joints_3d for f in est.frames], dtype=float)
    err, mirrored = frame_errors(j3, truth.joints_3d)
    return {"err_mm": 1000 * err, "mirrored": mirrored, "seconds": sec}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--noise", type=float, default=1.0)
    ap.add_argument("--schedules", default="moving,still")
    ap.add_argument("--variants", default="without,with", help="comma list of without / with (the prior)")
    ap.add_argument("--weight", type=float, default=None, help="the prior's weight (default signs_dp.PRIOR_WEIGHT)")
    ap.add_argument("--passes", type=int, default=None)
    ap.add_argument("--arbiter", type=float, default=None, help="pipeline.PRIOR_ARBITER_WEIGHT")
    ap.add_argument("--arms", type=float, default=None, help="signs_dp.PRIOR_ARM_FACTOR")
    ap.add_argument("--legs-alone", type=int, default=None, help="signs_dp.PRIOR_LEGS_ALONE (0 / 1)")
    ap.add_argument("--arm-cap", type=float, default=None, help="signs_dp.PRIOR_ARM_CAP")
    ap.add_argument("--cue-groups", default=None, help="signs_dp.CUE_GROUPS, comma list of first joints")
    add_model_arguments(ap, joint_solve=True)
    ap.add_argument("--sigmas", default=None, help="solver sigmas to change, e.g. accel_ms2=60,foot_m=0.01")
    args = ap.parse_args(argv)
    apply_model_arguments(args)
    if args.sigmas:
        import dataclasses

        changes = {k: float(v) for k, v in (a.split("=") for a in args.sigmas.split(","))}
        default_sigmas = pipeline._sigmas
        pipeline._sigmas = lambda static: dataclasses.replace(default_sigmas(static), **changes)
    if args.cue_groups is not None:
        signs_dp.CUE_GROUPS = tuple(args.cue_groups.split(","))
    if args.arm_cap is not None:
        signs_dp.PRIOR_ARM_CAP = args.arm_cap
    if args.weight is not None:
        signs_dp.PRIOR_WEIGHT = args.weight
    if args.passes is not None:
        signs_dp.PRIOR_PASSES = args.passes
    if args.arbiter is not None:
        pipeline.PRIOR_ARBITER_WEIGHT = args.arbiter
    if args.arms is not None:
        signs_dp.PRIOR_ARM_FACTOR = args.arms
    if args.legs_alone is not None:
        signs_dp.PRIOR_LEGS_ALONE = bool(args.legs_alone)
    clips = [c for c in list(args.clips) + ["builtin:walk", "builtin:run"]
             if args.half == "both" or half_of(c) == args.half]
    total: dict = {}
    for schedule in args.schedules.split(","):
        for clip in clips:
            parts = []
            for variant in args.variants.split(","):
                r = run_case(clip, schedule, args.frames, args.noise, variant == "with")
                total.setdefault((schedule, variant), []).append(r)
                parts.append(f"{variant}: {np.mean(r['err_mm']):.1f} mm, mirrored "
                             f"{100 * np.mean(r['mirrored']):.0f} %, {r['seconds']:.1f} s")
            print(f"{schedule} {os.path.basename(clip)}: " + "; ".join(parts), flush=True)
    print(f"\n| {args.half} half | prior | clips | P-MPJPE per frame mm (mean of clips) | frames with a mirrored "
          "limb | seconds per clip |")
    print("|---|---|---|---|---|---|")
    for (schedule, variant), rows in total.items():
        e = np.mean([np.mean(r["err_mm"]) for r in rows])
        m = 100 * np.mean(np.concatenate([r["mirrored"] for r in rows]))
        s = np.mean([r["seconds"] for r in rows])
        print(f"| {schedule} | {variant} | {len(rows)} | {e:.1f} | {m:.1f} % | {s:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
