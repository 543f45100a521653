"""Track Background on painted footage: what Blender's tracker keeps, and the camera solved with it.

Each case films a built-in motion (or a BVH clip) with a handheld operator and an unknown lens, with N
static scene points; paints the frames with numpy (each point and joint a textured patch, the joints over
the points, ``core.synthetic.footage_sim.painted``); runs Track Background on the clip (Blender's detector and
tracker, ``blender.background_tracking``; the time it takes is what the default background adds to a run,
beside the estimate's own difference with and without it); and estimates the joint method three ways: with the tracked
background, with the generator's own static tracks (the points at the tracks' 1 px noise), and from the
person alone. The frames are painted from the same shot without noise; the joint tracks carry 1 px.
Runs with Blender's Python or the PyPI ``bpy`` module:

    python bench/background_bench.py [BVH ...] [--cases 3] [--first 3] [--frames 300] [--points 24] [--json OUT]

Settings were chosen on cases 0-2 of the built-in walk and run; ``--first 3`` reports other cases.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def _case(clip: str, k: int) -> dict:
    rng = np.random.default_rng(1000 + k)
    return {"clip": clip, "seed": int(rng.integers(1 << 30)),
            "focal_mm": float(np.exp(rng.uniform(np.log(18), np.log(85)))),
            "moves_per_s": float(rng.uniform(0.5, 2.0)), "view_offset_deg": float(rng.uniform(-60, 60))}


def run_case(c: dict, frames: int, points: int) -> dict:
    import bpy

    import extension_loader

    extension_loader.load_extension()
    from monoskel.blender.background_tracking import track_background
    from monoskel.core.estimate import estimate
    from monoskel.core.evaluation.evaluate import score
    from monoskel.core.evaluation.metrics import followed_point_errors_px
    from monoskel.core.synthetic.footage_sim import HandheldOperator
    from monoskel.core.synthetic.footage_sim.painted import paint_frames, write_png_sequence
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    motion = load_motion(c["clip"], fps=30.0, max_frames=frames)
    filmed, truth = synthesize(motion, kinds=(), focal_mm=c["focal_mm"], noise_px=1.0, seed=c["seed"],
                               view_offset_deg=c["view_offset_deg"],
                               operator=HandheldOperator(moves_per_s=c["moves_per_s"]), static_points=points)
    # the footage shows the scene where it is: painted from the same shot without the tracks' noise
    clean, _ = synthesize(motion, kinds=(), focal_mm=c["focal_mm"], noise_px=0.0, seed=c["seed"],
                          view_offset_deg=c["view_offset_deg"],
                          operator=HandheldOperator(moves_per_s=c["moves_per_s"]), static_points=points)
    joints = filmed.replaced(static=None)
    row = dict(c, frames=filmed.n_frames)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        paths = np.concatenate([clean.static.xy, clean.xy], axis=1)
        zoom = truth.focal_mm / truth.focal_mm[0]
        write_png_sequence(paint_frames(paths, filmed.image_size, turn_deg_per_frame=0.0, seed=c["seed"] % 997,
                                        zoom=zoom), tmp, stem="shot")
        row["paint_s"] = time.perf_counter() - t0
        bpy.ops.wm.read_factory_settings(use_empty=True)
        clip = bpy.data.movieclips.load(os.path.join(tmp, "shot_0001.png"))
        bpy.context.scene.active_clip = clip
        t0 = time.perf_counter()
        static, report = track_background(bpy.context, clip, joints)
        row["track_s"] = time.perf_counter() - t0
    row.update(kept=report.kept, live_median=report.live_median, frames_under_four=report.frames_under_four,
               fallback=report.fallback)
    if static is not None:
        _, errs = followed_point_errors_px(static.xy, clean.static.xy)
        row["motion_err_px_median"] = float(np.median(errs))
        row["motion_err_px_max"] = float(np.max(errs))
    for name, tracks in (("tracked", joints.replaced(static=static) if static is not None else None),
                         ("generator", filmed), ("person", joints)):
        if tracks is None:
            continue
        t0 = time.perf_counter()
        sc = score(estimate(tracks, "joint"), truth)
        row[f"{name}_s"] = time.perf_counter() - t0
        row[f"{name}_rot_deg"] = sc["rotation_error_deg"]
        row[f"{name}_mean_pp"] = sc["proportions"]["mean_abs"]
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*", help="BVH files (default: the built-in walk and run)")
    ap.add_argument("--cases", type=int, default=3, help="cases per clip (default 3)")
    ap.add_argument("--first", type=int, default=0,
                    help="first case number (default 0): settings were chosen on cases 0-2, report from 3 on")
    ap.add_argument("--frames", type=int, default=300, help="frames per case (default 300, 10 s at 30 fps)")
    ap.add_argument("--points", type=int, default=24, help="static scene points painted (default 24)")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    clips = args.clips or ["builtin:walk", "builtin:run"]
    rows = []
    for clip in clips:
        for k in range(args.first, args.first + args.cases):
            r = run_case(_case(clip, k), args.frames, args.points)
            rows.append(r)
            print(f"{os.path.basename(r['clip']):24s} {r['focal_mm']:4.0f} mm {r['moves_per_s']:.1f} moves/s | kept "
                  f"{r['kept']:3d}, {r['live_median']:4.1f} in view, {r['frames_under_four']:3d} frames < 4, motion "
                  f"{r.get('motion_err_px_median', np.nan):.2f} / {r.get('motion_err_px_max', np.nan):.2f} px"
                  f" | rotation tracked {r.get('tracked_rot_deg', float('nan')):.3f}, generator "
                  f"{r['generator_rot_deg']:.3f}, person {r['person_rot_deg']:.3f} deg | track {r['track_s']:.1f} s "
                  f"for {r['frames']} frames, estimate {r.get('tracked_s', np.nan) - r['person_s']:+.1f} s with it"
                  + (f" | FELL BACK: {r['fallback']}" if r.get("fallback") else ""), flush=True)
    med = {k: float(np.nanmedian([r.get(k, np.nan) for r in rows])) for k in
           ("tracked_rot_deg", "generator_rot_deg", "person_rot_deg", "live_median", "motion_err_px_max", "track_s",
            "tracked_mean_pp", "generator_mean_pp", "person_mean_pp", "tracked_s", "person_s")}
    print(f"\nmedian over {len(rows)} cases: rotation tracked {med['tracked_rot_deg']:.3f} / generator "
          f"{med['generator_rot_deg']:.3f} / person {med['person_rot_deg']:.3f} deg; proportions "
          f"{med['tracked_mean_pp']:.2f} / {med['generator_mean_pp']:.2f} / {med['person_mean_pp']:.2f} pp; "
          f"{med['live_median']:.0f} in view; worst motion error {med['motion_err_px_max']:.2f} px; "
          f"tracking {med['track_s']:.1f} s (the time the default background adds, with the estimate's "
          f"{med['tracked_s'] - med['person_s']:+.1f} s); {sum(bool(r.get('fallback')) for r in rows)} fell back")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"rows": rows, "median": med}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
