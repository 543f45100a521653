"""``python -m core evaluate``: the paper's experiment, scored against truth.

For every clip (BVH files, or the built-in walk) the generator films the rigid
figure with a still/pan/tilt/zoom camera and noise; every requested method
estimates from the 2D tracks alone; the result is compared with the truth and
printed as a Table-1-style table (class, actual %, estimated %, error in
percentage points) plus camera-spell detection, stance accuracy, virtual-scale
error and, where a method gives them, the focal, rotation and 3D-pose errors.
A method that fails prints its error and the others carry on.  ``--plot-dir``
writes the paper's Figure 8 (estimated vs actual virtual scale) per clip/method.
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

from ..errors import InputError
from ..estimate import METHODS, estimate
from ..io.file_io import check_output_file, write_json_atomic
from ..skeleton import CLASSES
from . import metrics

BUILTIN_CLIPS = ("builtin:walk",)
ZOOM_KINDS = ("zoom", "rotate_zoom")


def add_arguments(parser) -> None:
    parser.add_argument("clips", nargs="*", metavar="BVH", help="BVH files (default: --builtin)")
    parser.add_argument("--builtin", action="store_true", help="use the built-in walk")
    parser.add_argument("--method", default="paper,joint",
                        help="comma-separated methods, side by side (default: paper,joint)")
    parser.add_argument("--noise-px", type=float, default=1.0, help="2D noise, pixels (standard deviation)")
    parser.add_argument("--kinds", default="pan,tilt,zoom", help="camera motion kinds of the schedule")
    parser.add_argument("--continuous", action="store_true",
                        help="no still spells between camera motions (beyond the paper's assumption)")
    parser.add_argument("--dropout", type=float, default=0.0,
                        help="fraction of joint observations dropped at random (default 0)")
    parser.add_argument("--occlusion-s", type=float, default=0.0,
                        help="seconds a random limb is hidden, per occlusion event (default 0)")
    parser.add_argument("--max-frames", type=int, default=None, help="truncate every clip (after resampling)")
    parser.add_argument("--fps", type=float, default=30.0, help="resample clips to this frame rate (video rate)")
    parser.add_argument("--focal-mm", type=float, default=50.0, help="frame-0 focal length of the virtual camera")
    parser.add_argument("--hint-focal", action="store_true",
                        help="give the methods the true frame-0 focal length (default: no hint)")
    parser.add_argument("--plot-dir", default=None, help="write Figure-8 PNGs here")
    parser.add_argument("--seed", type=int, default=0, help="camera schedule and noise draw (default 0)")
    parser.add_argument("--seeds", default=None, metavar="0,1,2",
                        help="several draws, each clip filmed once per seed; the summary adds a pooled line "
                             "per method (overrides --seed)")
    parser.add_argument("--json", default=None, metavar="OUT.json", help="write all numbers as JSON")


def zoom_mask(truth) -> np.ndarray:
    mask = np.zeros(truth.n_frames, dtype=bool)
    for s in truth.spells:
        if s.kind in ZOOM_KINDS:
            mask[s.start:s.end + 1] = True
    return mask


def score(est, truth) -> dict:
    """Every metric that applies to ``est`` against ``truth``."""
    out: dict = {"proportions": metrics.proportion_errors_pp(est.proportions_vector(), truth.proportions)}
    out["estimated_proportions"] = {c: float(v) for c, v in zip(CLASSES, est.proportions_vector())}
    moving = np.array([f.camera_moving for f in est.frames])
    out["spells"] = metrics.spell_detection(moving, truth.camera_moving)
    out["stance_accuracy"] = metrics.stance_accuracy([f.stance for f in est.frames], truth.stance,
                                                      truth.stance_clear)
    out["scale_error"] = metrics.scale_error(np.array([f.scale for f in est.frames]), truth.scale)
    out["focal0_error_pct"] = metrics.focal_error_pct(est.focal_mm, float(truth.focal_mm[0]))
    out["focal_determined"] = est.diagnostics.get("focal_determined")
    out["zoom_focal_error_pct"] = metrics.zoom_focal_error_pct(np.array([f.focal_mm for f in est.frames]),
                                                              truth.focal_mm, zoom_mask(truth))
    out["rotation_error_deg"] = metrics.rotation_error_deg(np.array([f.rotvec_deg for f in est.frames]),
                                                           truth.rotvec_deg)
    if all(f.joints_3d is not None for f in est.frames):
        j3 = np.array([f.joints_3d for f in est.frames], dtype=float)
        out["mpjpe_frame_mm"] = metrics.mpjpe_per_frame_m(j3, truth.joints_3d) * 1000.0
        out["mpjpe_clip_mm"] = metrics.mpjpe_clip_m(j3, truth.joints_3d) * 1000.0
    return out


def score_applies(v) -> bool:
    """Whether a score applies: ``score`` gives None or NaN where a clip has no zoom or no clear stance."""
    return v is not None and not (isinstance(v, float) and math.isnan(v))


def format_score(v, spec: str = ".2f") -> str:
    """A score formatted with ``spec``, or "-" where it does not apply (:func:`score_applies`)."""
    return format(v, spec) if score_applies(v) else "-"


def _focal_assumed(sc: dict) -> bool:
    """Whether the scored f0 error measures the hint or the 50 mm default rather than an estimate: a
    method that says it did not determine the focal length must not look calibrated because the
    default was right.  Marked in the clip table, the summary and its footnote."""
    return sc.get("focal_determined") is False


def print_clip_table(name: str, method: str, truth, est, sc: dict, seconds: float, out=None) -> None:
    out = out if out is not None else sys.stdout  # looked up per call: a default bound at import goes stale
    print(f"\n== {name} | method {method} | {truth.n_frames} frames | {seconds:.2f} s", file=out)
    print(f"{'class':<12} {'actual %':>9} {'estimated %':>12} {'error pp':>9}", file=out)
    est_p = est.proportions_vector()
    for i, c in enumerate(CLASSES):
        print(f"{c:<12} {truth.proportions[i] * 100:9.2f} {est_p[i] * 100:12.2f} "
              f"{sc['proportions']['per_class'][c]:+9.2f}", file=out)
    p = sc["proportions"]
    sp = sc["spells"]
    print(f"mean |error| {p['mean_abs']:.2f} pp, max {p['max_abs']:.2f} pp", file=out)
    kinds = [s.get("kind") for s in est.diagnostics.get("spells", [])]
    true_kinds = [s.kind for s in truth.spells]
    print(f"camera spells: moving-frame accuracy {sp['frame_accuracy'] * 100:.1f} %, boundaries found "
          f"{sp['boundary_recall'] * 100:.0f} % (within 5 frames), mean offset "
          f"{format_score(sp['boundary_offset_frames'], '.1f')} frames", file=out)
    print(f"  spells true {'/'.join(true_kinds)}", file=out)
    print(f"  spells est. {'/'.join(str(k) for k in kinds) if kinds else '-'}", file=out)
    assumed = " (not determined: hint or default)" if _focal_assumed(sc) else ""
    print(f"stance accuracy {format_score(sc['stance_accuracy'] * 100, '.1f')} % | virtual scale error "
          f"{sc['scale_error'] * 100:.2f} % | focal f0 error {sc['focal0_error_pct']:+.2f} %{assumed} | "
          "zoom focal error "
          f"{format_score(sc['zoom_focal_error_pct'])} % | rotation error (median) {sc['rotation_error_deg']:.3f} deg",
          file=out)
    if "mpjpe_frame_mm" in sc:
        print(f"3D MPJPE: per-frame similarity {sc['mpjpe_frame_mm']:.1f} mm, clip similarity "
              f"{sc['mpjpe_clip_mm']:.1f} mm", file=out)


def print_summary(rows: list[dict], out=None, unit: str = "clips") -> None:
    out = out if out is not None else sys.stdout
    print("\n== summary", file=out)
    head = (f"{'clip':<44} {'method':<7} {'mean pp':>7} {'max pp':>7} {'moving%':>8} {'stance%':>8} "
            f"{'scale%':>7} {'f0 %':>6} {'zoomf%':>7} {'rot deg':>8} {'mpjpe':>6} {'mpjpeC':>7} {'sec':>6}")
    print(head, file=out)
    for r in rows:
        if "error" in r:
            print(f"{r['clip'][:44]:<44} {r['method']:<7} FAILED: {r['error']}", file=out)
            continue
        s = r["score"]
        print(f"{r['clip'][:44]:<44} {r['method']:<7} {s['proportions']['mean_abs']:7.2f} "
              f"{s['proportions']['max_abs']:7.2f} {s['spells']['frame_accuracy'] * 100:8.1f} "
              f"{format_score(s['stance_accuracy'] * 100, '.1f'):>8} {s['scale_error'] * 100:7.2f} "
              f"{s['focal0_error_pct']:5.2f}{'*' if _focal_assumed(s) else ' '} "
              f"{format_score(s['zoom_focal_error_pct']):>7} {s['rotation_error_deg']:8.3f} "
              f"{format_score(s.get('mpjpe_frame_mm'), '.1f'):>6} {format_score(s.get('mpjpe_clip_mm'), '.1f'):>7} "
              f"{r['seconds']:6.2f}", file=out)
    for method, scores in _scores_by_method(rows).items():
        a = pooled(scores)
        label = f"ALL ({a['runs']} {unit})"
        print(f"{label:<44} {method:<7} {a['mean_pp']:7.2f} {a['max_pp']:7.2f}   "
              f"(mean of the means, max of the maxima)", file=out)
    if any(_focal_assumed(r.get("score", {})) for r in rows):
        print("* f0 % of a method that did not determine the focal length: the error of the hint or of the "
              "50 mm default, not of an estimate", file=out)


def _scores_by_method(rows: list[dict]) -> dict[str, list[dict]]:
    """The scores of the rows that ran, per method in the order first met; a method whose every run
    failed is left out."""
    out: dict[str, list[dict]] = {m: [] for m in dict.fromkeys(r["method"] for r in rows)}
    for r in rows:
        if "score" in r:
            out[r["method"]].append(r["score"])
    return {m: scores for m, scores in out.items() if scores}


def parse_seeds(text: str) -> list[int]:
    """``"0,1,2"`` -> ``[0, 1, 2]``; an empty or malformed list is an :class:`InputError`."""
    try:
        seeds = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise InputError(f"--seeds: expected comma-separated integers, got {text!r}") from None
    if not seeds:
        raise InputError("--seeds: no seed given")
    return list(dict.fromkeys(seeds))


def pooled(scores: list[dict]) -> dict:
    """The benchmark's aggregates over runs (clips x seeds): mean of the run means and max of the run maxima
    (pp), median of the runs' median rotation errors and of their zoom focal errors, mean stance
    accuracy, and mean MPJPE per frame / whole clip where the method gives 3D."""
    zooms = [s["zoom_focal_error_pct"] for s in scores if score_applies(s["zoom_focal_error_pct"])]
    stances = [s["stance_accuracy"] for s in scores if score_applies(s["stance_accuracy"])]
    out = {"runs": len(scores),
           "mean_pp": float(np.mean([s["proportions"]["mean_abs"] for s in scores])),
           "max_pp": float(np.max([s["proportions"]["max_abs"] for s in scores])),
           "rotation_deg": float(np.median([s["rotation_error_deg"] for s in scores])),
           "zoom_focal_pct": float(np.median(zooms)) if zooms else float("nan"),
           "stance_pct": float(np.mean(stances)) * 100 if stances else float("nan")}
    if all("mpjpe_frame_mm" in s for s in scores):
        out["mpjpe_frame_mm"] = float(np.mean([s["mpjpe_frame_mm"] for s in scores]))
        out["mpjpe_clip_mm"] = float(np.mean([s["mpjpe_clip_mm"] for s in scores]))
    return out


def print_pooled(rows: list[dict], n_seeds: int, out=None) -> None:
    """One line per method over every clip and seed (:func:`pooled`): a single draw of the camera
    schedule can be kind or unkind to a method, so settings are compared on several."""
    out = out if out is not None else sys.stdout
    print(f"\n== pooled over {n_seeds} seeds (mean / max pp, median rotation deg, median zoom %, stance %, "
          "MPJPE frame / clip mm)", file=out)
    for method, scores in _scores_by_method(rows).items():
        a = pooled(scores)
        print(f"{method:<7} {a['runs']:3d} runs  {a['mean_pp']:.3f} / {a['max_pp']:.2f} pp  "
              f"{a['rotation_deg']:.2f} deg  {format_score(a['zoom_focal_pct'], '.1f')} %  "
              f"{format_score(a['stance_pct'], '.1f')} %  "
              f"{format_score(a.get('mpjpe_frame_mm'), '.0f')} / {format_score(a.get('mpjpe_clip_mm'), '.0f')} mm",
              file=out)


def run(args) -> int:
    from ..synthetic.motion import load_motion
    from ..synthetic.synth import synthesize
    from ..synthetic.synth_camera import check_kinds

    if args.json:
        check_output_file(args.json, "--json")
    clips = list(args.clips)
    if args.builtin or not clips:
        clips = list(BUILTIN_CLIPS) + clips
    methods = [m.strip() for m in args.method.split(",") if m.strip()]
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise InputError(f"unknown method(s) {unknown}; choose from {sorted(METHODS)}")
    kinds = check_kinds(args.kinds)
    if args.plot_dir:
        os.makedirs(args.plot_dir, exist_ok=True)
    seeds = parse_seeds(args.seeds) if args.seeds else [args.seed]
    rows: list[dict] = []
    for clip, seed in ((c, sd) for c in clips for sd in seeds):
        name = os.path.basename(clip) + (f" s{seed}" if len(seeds) > 1 else "")
        try:
            motion = load_motion(clip, max_frames=args.max_frames, fps=args.fps)
            tracks, truth = synthesize(motion, kinds=kinds, focal_mm=args.focal_mm, noise_px=args.noise_px,
                                       dropout=args.dropout, occlusion_s=args.occlusion_s, seed=seed,
                                       continuous=args.continuous)
        except InputError as exc:
            print(f"\n== {name}: cannot synthesize: {exc}", file=sys.stderr)
            rows.append({"clip": name, "method": "-", "error": str(exc)})
            continue
        hint = float(truth.focal_mm[0]) if args.hint_focal else None
        for method in methods:
            print(f"running {method} on {name} ({truth.n_frames} frames) ...", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            try:
                est = estimate(tracks, method, focal_mm=hint, height_m=truth.height_m)
            except Exception as exc:  # one method failing must not stop the others
                msg = f"{type(exc).__name__}: {exc}"
                print(f"\n== {name} | method {method}: FAILED: {msg}")
                rows.append({"clip": name, "method": method, "error": msg})
                continue
            seconds = time.perf_counter() - t0
            sc = score(est, truth)
            print_clip_table(name, method, truth, est, sc, seconds)
            sys.stdout.flush()
            rows.append({"clip": name, "method": method, "seed": seed, "frames": truth.n_frames, "seconds": seconds,
                         "score": sc})
            if args.plot_dir:
                from ..io.png_plot import write_scale_plot

                stem = os.path.splitext(name.replace("builtin:", "builtin_"))[0]
                plot_path = os.path.join(args.plot_dir, f"{stem.replace(' ', '_')}_{method}_scale.png")
                write_scale_plot(plot_path, truth.scale, np.array([f.scale for f in est.frames]))
                print(f"plot {plot_path}: virtual scale per frame, red actual, blue estimated (Figure 8)")
    print_summary(rows, unit="runs" if len(seeds) > 1 else "clips")
    if len(seeds) > 1:
        print_pooled(rows, len(seeds))
    if args.json:
        settings = {"noise_px": args.noise_px, "kinds": list(kinds), "continuous": bool(args.continuous),
                    "max_frames": args.max_frames, "fps": args.fps,
                    "seeds": seeds, "focal_mm": args.focal_mm, "hint_focal": bool(args.hint_focal),
                    "dropout": args.dropout, "occlusion_s": args.occlusion_s}
        write_json_atomic({"settings": settings, "results": rows}, args.json, what="evaluation results", indent=1,
                          default=float)
    return 0
