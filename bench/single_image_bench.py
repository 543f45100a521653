"""Single-image posing on frames of the clips: Taylor's method against the truth.

Every clip is filmed once (the paper's camera schedule, a random lens 18-85 mm, 1 px by default) and
every ``--every``-th frame is posed on its own, with the true class lengths, in four ways:

* ``true signs, Taylor``: the true depth signs at Taylor's default scale (the minimum), orthographic;
* ``true signs, trunk``: the same at the trunk's scale (:func:`core.single_image.family.scale_trunk`);
* ``true signs, perspective, Taylor``: the trunk's scale under perspective with the true focal length,
  Taylor's construction as it is;
* ``true signs, perspective``: the same polished by least squares (:mod:`core.single_image.refine`,
  the default under perspective);
* ``auto signs``: the signs chosen by :mod:`core.single_image.signs`, orthographic, the trunk's scale;
* ``auto, perspective``: the chosen signs under perspective with the true focal length.

Per frame: the mean joint error after a similarity alignment (P-MPJPE), and whether any of the 8 limb
segments points more than 45 degrees away from the truth after that alignment (a mirrored limb).
Clips are split as in ``bench/robust_bench.py``; the README quotes the report half.

    python bench/single_image_bench.py ../shared/data/bvh/*.bvh [--half report] [--noise-px 1]
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.model_options import add_model_arguments, apply_model_arguments  # noqa: E402
from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.camera import rotation_matrix  # noqa: E402
from core.evaluation.metrics import similarity_align  # noqa: E402
from core.single_image import pose_from_image  # noqa: E402
from core.single_image.family import depth_sign  # noqa: E402
from core.skeleton import LIMBS, SEGMENTS  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402

LIMB_SEGMENTS = [k for k, (_, c) in enumerate(SEGMENTS) if any(c in js[1:] for js in LIMBS.values())]


def true_signs(X: np.ndarray) -> dict:
    return {k: depth_sign(X[p], X[c]) for k, (p, c) in enumerate(SEGMENTS)}


def frame_scores(est: np.ndarray, truth: np.ndarray) -> tuple[float, bool]:
    ok = np.isfinite(est).all(axis=1)
    aligned = similarity_align(est[ok], truth[ok])
    full = np.full_like(est, np.nan)
    full[ok] = aligned
    err = float(np.mean(np.linalg.norm(aligned - truth[ok], axis=1)))
    mirrored = False
    for k in LIMB_SEGMENTS:
        p, c = SEGMENTS[k]
        a, b = full[c] - full[p], truth[c] - truth[p]
        if np.isfinite(a).all():
            cos = a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-12)
            mirrored |= bool(cos < np.cos(np.radians(45.0)))
    return err, mirrored


def run_clip(clip: str, every: int, noise: float, max_frames: int) -> dict:
    rng = _case_rng(clip, "single", 0)
    focal = float(np.exp(rng.uniform(np.log(18.0), np.log(85.0))))
    motion = load_motion(clip, fps=30.0, max_frames=max_frames)
    tracks, truth = synthesize(motion, focal_mm=focal, noise_px=noise, seed=int(rng.integers(1 << 30)))
    R = rotation_matrix(truth.rotvec_deg)
    rows = {k: [] for k in ("true signs, Taylor", "true signs, trunk", "true signs, perspective, Taylor",
                            "true signs, perspective", "auto signs", "auto, perspective")}
    for i in range(0, tracks.n_frames, every):
        if not tracks.present[i].all():
            continue
        X = truth.joints_3d[i] @ R[i].T                       # the frame's camera axes
        signs = true_signs(X)
        for name, kw in (("true signs, Taylor", {"signs": signs, "scale": "min"}),
                         ("true signs, trunk", {"signs": signs}),
                         ("true signs, perspective, Taylor", {"signs": signs, "focal_mm": float(truth.focal_mm[i]),
                                                              "refine": False}),
                         ("true signs, perspective", {"signs": signs, "focal_mm": float(truth.focal_mm[i])}),
                         ("auto signs", {}), ("auto, perspective", {"focal_mm": float(truth.focal_mm[i])})):
            pose = pose_from_image(tracks.xy[i], tracks.image_size, truth.class_lengths_m, **kw)
            rows[name].append(frame_scores(pose.joints, X))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--every", type=int, default=15, help="pose every n-th frame (default 15)")
    ap.add_argument("--noise-px", type=float, default=1.0)
    ap.add_argument("--max-frames", type=int, default=900)
    ap.add_argument("--prior-weight", type=float, default=None,
                    help="the pose prior's weight in the sign choice (core.single_image.signs.PRIOR_WEIGHT; 0: off)")
    ap.add_argument("--prior-bones", choices=["legs", "limbs"], default=None,
                    help="the bones the prior scores (core.single_image.signs.PRIOR_BONES)")
    ap.add_argument("--lifter-sigma", type=float, default=None,
                    help="the pose lifter's sigma in the sign choice (core.single_image.signs.LIFTER_SIGMA; 0: off)")
    add_model_arguments(ap, joint_solve=False)
    args = ap.parse_args(argv)
    apply_model_arguments(args)
    from core.single_image import signs as sign_choice

    if args.lifter_sigma is not None:
        sign_choice.LIFTER_SIGMA = args.lifter_sigma or None

    if args.prior_weight is not None:
        sign_choice.PRIOR_WEIGHT = args.prior_weight
    if args.prior_bones is not None:
        from core.motion_prior.features import LEG_BONES, LIMB_BONES

        sign_choice.PRIOR_BONES = LEG_BONES if args.prior_bones == "legs" else LIMB_BONES
    clips = [c for c in list(args.clips) + ["builtin:walk", "builtin:run"]
             if args.half == "both" or half_of(c) == args.half]
    total: dict = {}
    for clip in clips:
        rows = run_clip(clip, args.every, args.noise_px, args.max_frames)
        parts = []
        for name, vals in rows.items():
            total.setdefault(name, []).extend(vals)
            if vals:
                e = np.array([v[0] for v in vals]) * 1000
                m = np.mean([v[1] for v in vals]) * 100
                parts.append(f"{name}: {np.median(e):.0f} mm, mirrored {m:.0f} %")
        print(f"{os.path.basename(clip)} ({len(next(iter(rows.values())))} frames): " + "; ".join(parts), flush=True)
    print(f"\n| posing ({args.half} half, {args.noise_px:g} px) | frames | P-MPJPE mm median / mean / p90 | "
          "frames with a mirrored limb |")
    print("|---|---|---|---|")
    for name, vals in total.items():
        e = np.array([v[0] for v in vals]) * 1000
        m = np.mean([v[1] for v in vals]) * 100
        print(f"| {name} | {len(vals)} | {np.median(e):.1f} / {np.mean(e):.1f} / {np.quantile(e, 0.9):.1f} | "
              f"{m:.1f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
