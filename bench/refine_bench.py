"""Refine Tracks on Footage benchmark: Blender's tracker on painted footage of the shared clips.

Per clip: the motion filmed by a handheld operator (18-85 mm, 24/30/60 fps, 720x480 or 1280x720), each
joint painted as a textured patch about 6 % of the figure's height (``core.synthetic.footage_sim.painted``), and
a detector's errors on the exact joints (``TYPICAL``: outliers, left/right exchanges, per-joint
jitter, missing runs; noise 1-4 px). Compared with the truth: the detector's positions, a
Savitzky-Golay smoothing of them (0.2 s, quadratic; the obvious alternative), and the refined tracks
(tracking windows of 3, 5 and 10 frames on the tune half, the default 5 on the report half; disagreeing
detector positions kept, the default, or replaced by the tracked path's).

"Inliers" are entries the detector got within 5 noise levels; "gross" the others (outliers and
exchanged limbs), scored as the share brought within 3 noise levels. Runs inside real Blender (the
``bpy`` module); seconds are the tracker's and the fusion's per frame of 17 joints (the second policy
counts the tracking again).

With ``--estimate`` the default estimate runs on the detector's and on the refined tracks (the
default policy), scored against the truth.

    python bench/refine_bench.py ../shared/data/bvh/*.bvh [--half tune|report|both] [--seconds 4] [--estimate]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
from robust_bench import _case_rng, half_of  # noqa: E402
from scipy.signal import savgol_filter  # noqa: E402


def _addon():
    import bpy

    import extension_loader

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = extension_loader.load_extension()
    addon.register()
    return bpy


def draw(clip: str) -> dict:
    rng = _case_rng(clip, "refine", 0)
    return {"clip": clip, "seed": int(rng.integers(1 << 30)),
            "focal_mm": float(np.exp(rng.uniform(np.log(18.0), np.log(85.0)))),
            "fps": float(rng.choice([24.0, 30.0, 60.0])), "noise_px": float(rng.uniform(1.0, 4.0)),
            "size": [(720, 480), (1280, 720)][int(rng.integers(2))],
            "view_offset_deg": float(rng.uniform(-90.0, 90.0))}


def smoothed(xy: np.ndarray, fps: float) -> np.ndarray:
    """Savitzky-Golay over 0.2 s per joint and axis, gaps bridged linearly for the filter and kept."""
    win = max(5, int(round(0.2 * fps)) | 1)
    out = np.full_like(xy, np.nan)
    t = np.arange(len(xy))
    for j in range(xy.shape[1]):
        seen = np.isfinite(xy[:, j, 0])
        if seen.sum() < win:
            out[:, j] = xy[:, j]
            continue
        filled = np.stack([np.interp(t, t[seen], xy[seen, j, a]) for a in range(2)], axis=1)
        out[seen, j] = savgol_filter(filled, win, 2, axis=0)[seen]
    return out


def score(xy, truth, inlier, gross, sigma) -> dict:
    err = np.linalg.norm(xy - truth, axis=-1)
    ok = np.isfinite(err)
    return {"rms_px": float(np.sqrt(np.mean(err[inlier & ok] ** 2))),
            "gross_fixed": float(np.mean(ok[gross] & (np.nan_to_num(err[gross], nan=1e9) < 3 * sigma)))
            if gross.any() else float("nan")}


def end_to_end(tracks, truth) -> dict:
    """The default estimate from ``tracks`` scored against the truth (3D per frame, proportions)."""
    from monoskel.core.estimate import estimate
    from monoskel.core.evaluation.evaluate import score

    sc = score(estimate(tracks), truth)
    return {"mpjpe_mm": sc.get("mpjpe_frame_mm"), "mean_pp": sc["proportions"]["mean_abs"],
            "max_pp": sc["proportions"]["max_abs"]}


def run_clip(bpy, c: dict, windows, seconds: float, folder: str, with_estimate: bool = False) -> list[dict]:
    from monoskel.blender.track_refinement.tracker import track_runs
    from monoskel.core.synthetic.footage_sim import HandheldOperator
    from monoskel.core.synthetic.footage_sim.detector import TYPICAL, apply_detector_errors
    from monoskel.core.synthetic.footage_sim.painted import paint_frames, write_png_sequence
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.track_refinement import refine_tracks, seed_plan
    from monoskel.core.track_refinement.refine import figure_height

    motion = load_motion(c["clip"], fps=c["fps"], max_frames=int(round(seconds * c["fps"])))
    clean, truth = synthesize(motion, focal_mm=c["focal_mm"], noise_px=0.0, seed=c["seed"], image_size=c["size"],
                          view_offset_deg=c["view_offset_deg"], operator=HandheldOperator())
    visible = clean.present
    height = figure_height(clean)
    patch = int(np.clip(round(0.06 * height), 9, 41))
    frames = paint_frames(clean.xy, clean.image_size, patch_px=patch, seed=c["seed"] % 1000)
    for name in os.listdir(folder):
        os.remove(os.path.join(folder, name))
    write_png_sequence(frames, folder, stem="f")
    xy, conf, _ = apply_detector_errors(np.nan_to_num(clean.xy), visible, c["noise_px"], c["fps"], clean.image_size,
                                        TYPICAL, c["seed"])
    det = clean.replaced(xy=xy, conf=conf, source="detector")
    err = np.linalg.norm(det.xy - clean.xy, axis=-1)
    seen = det.present & visible
    inlier = seen & (err <= 5 * c["noise_px"])
    gross = seen & (err > 5 * c["noise_px"])
    base = {**{k: c[k] for k in ("clip", "fps", "noise_px", "focal_mm")}, "frames": det.n_frames,
            "figure_px": float(height), "patch_px": patch}
    rows = [{**base, "method": "detector", **score(det.xy, clean.xy, inlier, gross, c["noise_px"]),
             **(end_to_end(det, truth) if with_estimate else {})},
            {**base, "method": "savgol", **score(smoothed(det.xy, c["fps"]), clean.xy, inlier, gross,
                                                 c["noise_px"])}]
    for name in list(bpy.data.movieclips):
        bpy.data.movieclips.remove(name)
    clip = bpy.data.movieclips.load(os.path.join(folder, "f_0001.png"))
    for window in windows:
        t0 = time.perf_counter()
        runs = track_runs(bpy.context, clip, det, seed_plan(det, window), window)
        for policy in ("detector", "refined"):
            refined, report = refine_tracks(det, runs, disagree=policy)
            sec = time.perf_counter() - t0
            rows.append({**base, "method": f"w{window} {policy}", "seconds_per_frame": sec / det.n_frames,
                         "runs_dropped": report.runs_dropped, "disagreeing": report.disagreeing_entries,
                         **score(refined.xy, clean.xy, inlier, gross, c["noise_px"]),
                         **(end_to_end(refined, truth) if with_estimate and policy == "detector" else {})})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("clips", nargs="+")
    ap.add_argument("--half", default="both", choices=["tune", "report", "both"])
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--estimate", action="store_true",
                    help="also run the default estimate on the detector's and the refined tracks")
    ap.add_argument("--windows", default="", help="tracking windows to compare (default: 3,5,10 on tune, 5 on report)")
    args = ap.parse_args(argv)
    bpy = _addon()
    folder = tempfile.mkdtemp(prefix="refine_bench_")
    rows = []
    for clip in args.clips:
        half = half_of(clip)
        if args.half != "both" and half != args.half:
            continue
        windows = [int(w) for w in args.windows.split(",")] if args.windows else ([3, 5, 10] if half == "tune" else [5])
        c = draw(clip)
        for r in run_clip(bpy, c, windows, args.seconds, folder, args.estimate):
            r["half"] = half
            rows.append(r)
            extra = (f" {r['seconds_per_frame'] * 1000:.0f} ms/frame, {r['disagreeing']} disagreeing, "
                     f"{r['runs_dropped']} runs dropped") if "seconds_per_frame" in r else ""
            if "mpjpe_mm" in r:
                extra += f"; estimate {r['mpjpe_mm']:.0f} mm, {r['mean_pp']:.2f}/{r['max_pp']:.2f} pp"
            print(f"{half:6s} {os.path.basename(clip):22s} {r['fps']:4.0f} fps {r['noise_px']:.1f} px "
                  f"figure {r['figure_px']:4.0f} px  {r['method']:12s} inliers {r['rms_px']:5.2f} px  "
                  f"gross fixed {r['gross_fixed']:.2f}{extra}", flush=True)
    print()
    for half in ("tune", "report"):
        for method in sorted({r["method"] for r in rows if r["half"] == half}):
            sel = [r for r in rows if r["half"] == half and r["method"] == method]
            ratio = [r["rms_px"] / next(d["rms_px"] for d in rows if d["half"] == half and d["clip"] == r["clip"]
                                       and d["method"] == "detector") for r in sel]
            ms = [r["seconds_per_frame"] * 1000 for r in sel if "seconds_per_frame" in r]
            rms = np.median([r["rms_px"] for r in sel])
            print(f"{half:6s} {method:12s} clips {len(sel):2d}  inlier rms median {rms:.2f} px"
                  f"  vs detector median {np.median(ratio):.2f} (worst {max(ratio):.2f})"
                  f"  gross fixed {np.nanmedian([r['gross_fixed'] for r in sel]):.2f}"
                  + (f"  {np.median(ms):.0f} ms/frame" if ms else ""))
            est = [r for r in sel if r.get("mpjpe_mm") is not None]
            if est:
                mpjpe = np.median([r["mpjpe_mm"] for r in est])
                print(f"{'':6s} {'':12s} estimate: 3D per frame median {mpjpe:.0f} mm,"
                      f" proportions mean {np.mean([r['mean_pp'] for r in est]):.2f} / max "
                      f"{np.mean([r['max_pp'] for r in est]):.2f} pp (means over clips)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
