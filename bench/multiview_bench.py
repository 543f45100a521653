"""Multi-view benchmark: the shared clips filmed by 2, 3 and 4 static cameras round the person.

Per case: lenses 24-50 mm (36 mm film) at 1280x720, cameras 60-150 degrees apart on a ring, 1 px
noise, with or without a detector's errors (:data:`core.synthetic.footage_sim.detector.TYPICAL`), cameras given
or calibrated from the person.  Reported: per-frame MPJPE (each frame aligned on its own) and the
whole clip's (one alignment), proportion error, the self-calibrated lenses' error and the worst view's
pose error (rotation; centre as a share of its distance from view 1), seconds.

The thresholds of :mod:`core.multiview` were set on the built-in walk and on ``01_01``; the table in
the docs is the report half of ``bench/robust_bench.py``'s split without ``01_01``.

    python bench/multiview_bench.py ../shared/data/bvh/*.bvh [--half report] [--max-frames 600]
    python bench/multiview_bench.py --speed ../shared/data/bvh/bandai_dataset-1_dance-short_normal_001.bvh
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from core.errors import InputError  # noqa: E402
from core.evaluation.metrics import mpjpe_clip_m, mpjpe_per_frame_m  # noqa: E402
from core.multiview import estimate_multiview  # noqa: E402
from core.multiview.synth import film_views, ring_cameras  # noqa: E402
from core.skeleton import proportions  # noqa: E402
from core.synthetic.footage_sim.detector import TYPICAL  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from robust_bench import half_of  # noqa: E402

TUNED_ON = {"01_01.bvh", "builtin:walk"}


def pose_errors(found: list[dict], cams) -> tuple[float, float]:
    """Worst view's camera pose error against the truth, both in the first view's axes: rotation in
    degrees, and centre distance as a share of that camera's distance from the first (percent)."""
    from core.multiview.cameras import ViewCamera

    got = [ViewCamera.from_dict(c) for c in found]
    r0, c0 = cams[0].rotation, cams[0].position
    g0, h0 = got[0].rotation, got[0].position
    rot, pos = 0.0, 0.0
    for g, c in zip(got[1:], cams[1:]):
        r_true, r_got = c.rotation @ r0.T, g.rotation @ g0.T
        chord = np.linalg.norm(r_true - r_got) / (2.0 * np.sqrt(2.0))        # sin(angle / 2)
        rot = max(rot, float(np.degrees(2.0 * np.arcsin(min(chord, 1.0)))))
        p_true, p_got = r0 @ (c.position - c0), g0 @ (g.position - h0)
        pos = max(pos, float(np.linalg.norm(p_got - p_true) / np.linalg.norm(p_true) * 100.0))
    return rot, pos


def speed(clip: str, frames: int = 900, n_views: int = 4) -> int:
    """Seconds of one self-calibrated estimate of ``frames`` x ``n_views`` (1 px, no detector errors)."""
    motion = load_motion(clip, fps=30.0, max_frames=frames)
    if len(motion.joints) < frames:
        print(f"{clip} has only {len(motion.joints)} frames at 30 fps")
    cams = ring_cameras(motion, n_views, seed=0)
    views = film_views(motion, cams, noise_px=1.0, seed=0)
    t = time.perf_counter()
    est = estimate_multiview(views)
    sec = time.perf_counter() - t
    joints = np.array([f.joints_3d for f in est.frames])
    print(f"{os.path.basename(clip)}: {len(joints)} frames x {n_views} views, self-calibrated: {sec:.1f} s "
          f"(whole clip {1000 * mpjpe_clip_m(joints, cams[0].to_camera(motion.joints)):.1f} mm)")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--views", default="2,3,4", help="numbers of views to run")
    ap.add_argument("--gaps", default="60,150", help="range of the angles between neighbouring cameras (deg)")
    ap.add_argument("--clean-self", action="store_true",
                    help="only the cases without detector errors, cameras from the person")
    ap.add_argument("--speed", metavar="CLIP", help="only time 900 frames x 4 views, self-calibrated, on CLIP")
    args = ap.parse_args()
    if args.speed:
        return speed(args.speed)
    clips = [c for c in args.clips if (args.half == "both" or half_of(c) == args.half)
             and os.path.basename(c) not in TUNED_ON]
    rows = []
    for i, clip in enumerate(clips):
        motion = load_motion(clip, fps=30.0, max_frames=args.max_frames)
        for n_views in [int(v) for v in args.views.split(",")]:
            for det in (False,) if args.clean_self else (False, True):
                cams = ring_cameras(motion, n_views, seed=i, gap_deg=tuple(float(g) for g in args.gaps.split(",")))
                views = film_views(motion, cams, noise_px=1.0, detector=TYPICAL if det else None, seed=i)
                truth = cams[0].to_camera(motion.joints)
                for given in (False,) if args.clean_self else (True, False):
                    t = time.perf_counter()
                    try:
                        est = estimate_multiview(views, cameras=cams if given else None)
                    except InputError as exc:
                        print(f"{os.path.basename(clip):44s} {n_views} views {'det' if det else 'clean'} "
                              f"{'given' if given else 'self'}: refused: {exc}", flush=True)
                        rows.append({"views": n_views, "det": det, "given": given, "failed": True})
                        continue
                    sec = time.perf_counter() - t
                    joints = np.array([f.joints_3d for f in est.frames])
                    pp = 100 * np.abs(est.proportions_vector() - proportions(motion.class_lengths))
                    focal = [c["focal_px"] for c in est.diagnostics["cameras"]]
                    ferr = float(np.max(np.abs(np.array(focal) / [c.focal_px for c in cams] - 1)) * 100)
                    rot_err, pos_err = pose_errors(est.diagnostics["cameras"], cams)
                    r = {"views": n_views, "det": det, "given": given,
                         "frame_mm": 1000 * mpjpe_per_frame_m(joints, truth),
                         "clip_mm": 1000 * mpjpe_clip_m(joints, truth), "mean_pp": pp.mean(), "max_pp": pp.max(),
                         "focal_pct": ferr, "rot_deg": rot_err, "pos_pct": pos_err,
                         "sec": sec, "frames": len(joints), "failed": False}
                    rows.append(r)
                    print(f"{os.path.basename(clip):44s} {n_views} views {'det  ' if det else 'clean'} "
                          f"{'given' if given else 'self '} {r['frame_mm']:6.1f} / {r['clip_mm']:6.1f} mm  "
                          f"{r['mean_pp']:.2f} / {r['max_pp']:.2f} pp  lens {ferr:5.1f} %  pose {rot_err:.2f} deg "
                          f"{pos_err:.1f} %  {sec:5.1f} s "
                          f"({len(joints)} frames)", flush=True)
    print("\n| views | detector errors | cameras | cases | per frame mm | whole clip mm | proportions mean / max pp "
          "| worst lens error % | worst pose deg / % of distance | seconds | refused |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n_views in sorted({r["views"] for r in rows}):
        for det in (False, True):
            for given in (True, False):
                rs = [r for r in rows if (r["views"], r["det"], r["given"]) == (n_views, det, given)]
                ok = [r for r in rs if not r["failed"]]
                if not ok:
                    continue

                def med(k, ok=ok):
                    return float(np.median([r[k] for r in ok]))

                source = "given" if given else "from the person"
                print(f"| {n_views} | {'on' if det else 'off'} | {source} | {len(rs)} | "
                      f"{med('frame_mm'):.1f} | {med('clip_mm'):.1f} | {med('mean_pp'):.2f} / {med('max_pp'):.2f} | "
                      f"{'-' if given else format(med('focal_pct'), '.1f')} | "
                      f"{'-' if given else format(med('rot_deg'), '.2f') + ' / ' + format(med('pos_pct'), '.1f')} | "
                      f"{med('sec'):.1f} | "
                      f"{len(rs) - len(ok)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
