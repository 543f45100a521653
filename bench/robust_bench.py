"""Unseen-footage benchmark: randomized cases, split in a tuning half and a report half by file name.

Every clip (BVH files given on the command line, plus the built-in walk and run) is filmed in
several randomized cases:

* ``target``: the condition the robustness targets are set for - a handheld operator
  (:mod:`core.synthetic.footage_sim.handheld`), a lens drawn from 18-85 mm that the estimator is not
  told, 30 fps, 1 px noise plus a real detector's errors
  (:data:`core.synthetic.footage_sim.detector.TYPICAL`: 1 % outliers, 5 % of frames with a left/right
  exchange, extremity jitter, missing runs, confidence falling with error), a random azimuth;
* ``broad``: everything a user varies drawn at random - operator (tripod schedule or handheld),
  lens 18-85 mm, frame rate 24-120, noise 0.5-3 px, detector errors on or off, azimuth;
* ``fps``: one clip filmed identically at 30 and at 120 fps (0.5 px, no detector errors): the
  proportion and camera differences between the two.

The split: a clip belongs to the ``tune`` half when the first byte of the SHA-1 of its file name
is even, else to the ``report`` half.  Settings are chosen on ``tune`` only; the README and
docs/robustness.md quote ``report``.

    python bench/robust_bench.py ../shared/data/bvh/*.bvh [--half tune|report|both] [--draws 2]
        [--methods joint,paper] [--json OUT.json] [--max-frames 900]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from core.errors import InputError  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation.evaluate import score  # noqa: E402
from core.synthetic.footage_sim import HandheldOperator  # noqa: E402
from core.synthetic.footage_sim.detector import TYPICAL, DetectorErrors  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402

#: Limits that make a clip "should not be trusted": the self-check should flag it.
BAD_ROTATION_DEG = 2.0
BAD_MAX_PP = 3.0
BAD_MPJPE_MM = 150.0


def half_of(clip: str) -> str:
    name = os.path.basename(clip)
    return "tune" if hashlib.sha1(name.encode()).digest()[0] % 2 == 0 else "report"


def _case_rng(clip: str, case: str, draw: int) -> np.random.Generator:
    digest = hashlib.sha1(f"{os.path.basename(clip)}|{case}|{draw}".encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def draw_case(clip: str, case: str, draw: int) -> dict:
    rng = _case_rng(clip, case, draw)
    c = {"clip": clip, "case": case, "draw": draw, "seed": int(rng.integers(1 << 30)),
         "focal_mm": float(np.exp(rng.uniform(np.log(18.0), np.log(85.0)))),
         "view_offset_deg": float(rng.uniform(-90.0, 90.0))}
    if case == "target":
        c.update(operator="handheld", fps=30.0, noise_px=1.0, detector=True)
    elif case == "broad":
        c.update(operator=str(rng.choice(["tripod", "handheld"])),
                 fps=float(rng.choice([24.0, 25.0, 30.0, 50.0, 60.0, 120.0])),
                 noise_px=float(rng.uniform(0.5, 3.0)), detector=bool(rng.random() < 0.5))
    else:
        raise ValueError(case)
    return c


def film_case(c: dict, max_s: float):
    """(tracks, truth) of case ``c`` (:func:`draw_case`): its clip's first ``max_s`` seconds filmed as drawn."""
    motion = load_motion(c["clip"], fps=c["fps"], max_frames=int(round(max_s * c["fps"])))
    return synthesize(
        motion, focal_mm=c["focal_mm"], noise_px=c["noise_px"], seed=c["seed"],
        view_offset_deg=c["view_offset_deg"],
        operator=HandheldOperator() if c["operator"] == "handheld" else None,
        detector=TYPICAL if c["detector"] else DetectorErrors(), static_points=c.get("static_points", 0))


def run_case(c: dict, methods: list[str], max_s: float, raw: bool = False, second_pass: bool = True) -> list[dict]:
    tracks, truth = film_case(c, max_s)
    rows = []
    for m in methods:
        t0 = time.perf_counter()
        try:
            if raw:
                est = estimate(tracks, m, cleaning=None, working_rate=False)
            else:
                est = estimate(tracks, m) if second_pass else estimate(tracks, m, residual=None)
        except InputError as exc:
            rows.append({**c, "method": m, "error": str(exc)})
            continue
        sec = time.perf_counter() - t0
        sc = score(est, truth)
        flags = [f["code"] for f in est.diagnostics.get("self_check", {}).get("flags", [])]
        row = {**c, "method": m, "frames": tracks.n_frames, "seconds": sec,
               "mean_pp": sc["proportions"]["mean_abs"], "max_pp": sc["proportions"]["max_abs"],
               "rotation_deg": sc["rotation_error_deg"], "stance": sc["stance_accuracy"],
               "mpjpe_mm": sc.get("mpjpe_frame_mm"), "flags": flags,
               "warnings": list(est.diagnostics.get("warnings", [])),
               "check_metrics": {k: v for k, v in est.diagnostics.get("self_check", {}).get("metrics", {}).items()
                                 if not isinstance(v, dict)}}
        rows.append(row)
    return rows


def is_bad(r: dict) -> bool:
    rot = r.get("rotation_deg")
    mp = r.get("mpjpe_mm")
    return bool((rot is not None and rot > BAD_ROTATION_DEG) or r["max_pp"] > BAD_MAX_PP
                or (mp is not None and mp > BAD_MPJPE_MM))


def _q(values, q):
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.quantile(v, q)) if v else float("nan")


def summarize(rows: list[dict], out=sys.stdout) -> None:
    print("\n| half | case | method | cases | proportions mean / max pp (median case) | rotation deg median / p95 case "
          "| MPJPE mm median | stance % median | bad flagged | good flagged | sec median |", file=out)
    print("|---|---|---|---|---|---|---|---|---|---|---|", file=out)
    keys = sorted({(r["half"], r["case"], r["method"]) for r in rows if "error" not in r})
    for h, case, m in keys:
        rs = [r for r in rows if (r["half"], r["case"], r["method"]) == (h, case, m) and "error" not in r]
        bad = [r for r in rs if is_bad(r)]
        good = [r for r in rs if not is_bad(r)]
        bf = sum(1 for r in bad if r["flags"])
        gf = sum(1 for r in good if r["flags"])
        mp = _q([r["mpjpe_mm"] for r in rs], 0.5)
        print(f"| {h} | {case} | {m} | {len(rs)} | {_q([r['mean_pp'] for r in rs], .5):.2f} / "
              f"{_q([r['max_pp'] for r in rs], .5):.2f} | {_q([r['rotation_deg'] for r in rs], .5):.2f} / "
              f"{_q([r['rotation_deg'] for r in rs], .95):.2f} | {'-' if not np.isfinite(mp) else f'{mp:.0f}'} | "
              f"{100 * _q([r['stance'] for r in rs], .5):.1f} | {bf}/{len(bad)} | {gf}/{len(good)} | "
              f"{_q([r['seconds'] for r in rs], .5):.1f} |", file=out)
    errors = [r for r in rows if "error" in r]
    for r in errors:
        print(f"error: {os.path.basename(r['clip'])} {r['case']} {r['method']}: {r['error']}", file=out)


def fps_pairs(clips: list[str], max_s: float, out=sys.stdout, redraws: int = 0) -> list[dict]:
    """The same motion at 30 and 120 fps: proportion and camera differences (joint method).

    ``redraws``: also film each rate again that many times with the same camera schedule and new noise
    (seeds 1, 2, ...): how far a new noise draw alone moves the answer, the yardstick for the pair."""
    rows = []
    for clip in clips:
        res, again = {}, {30.0: [], 120.0: []}
        for fps in (30.0, 120.0):
            motion = load_motion(clip, fps=fps, max_frames=int(round(max_s * fps)))
            tracks, truth = synthesize(motion, noise_px=0.5, seed=0)
            est = estimate(tracks, "joint")
            res[fps] = (est.proportions_vector(), score(est, truth)["rotation_error_deg"])
            for seed in range(1, redraws + 1):
                t2, tr2 = synthesize(motion, noise_px=0.5, seed=seed, schedule=truth.spells)
                e2 = estimate(t2, "joint")
                again[fps].append((float(np.mean(np.abs(e2.proportions_vector() - res[fps][0])) * 100),
                                   float(abs(score(e2, tr2)["rotation_error_deg"] - res[fps][1]))))
        d_pp = float(np.mean(np.abs(res[30.0][0] - res[120.0][0])) * 100)
        d_rot = float(abs(res[30.0][1] - res[120.0][1]))
        row = {"clip": clip, "half": half_of(clip), "diff_mean_pp": d_pp, "diff_rotation_deg": d_rot}
        extra = ""
        if redraws:
            row["redraw"] = {str(int(k)): v for k, v in again.items()}
            extra = "; new noise alone: " + ", ".join(
                f"{int(k)} fps {max(a[0] for a in v):.3f} pp / {max(a[1] for a in v):.2f} deg"
                for k, v in again.items())
        rows.append(row)
        print(f"fps 30 vs 120  {os.path.basename(clip):<48} {half_of(clip):<6} proportions {d_pp:.3f} pp, "
              f"rotation error {res[30.0][1]:.2f} vs {res[120.0][1]:.2f} deg{extra}", file=out, flush=True)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*", help="BVH files (the built-in walk and run are always added)")
    ap.add_argument("--half", default="both", choices=["tune", "report", "both"])
    ap.add_argument("--draws", type=int, default=2, help="target-case draws per clip (default 2)")
    ap.add_argument("--broad", type=int, default=1, help="broad-case draws per clip (default 1)")
    ap.add_argument("--methods", default="joint,paper")
    ap.add_argument("--max-s", type=float, default=30.0, help="seconds of each clip (default 30)")
    ap.add_argument("--no-fps", action="store_true", help="skip the 30 vs 120 fps pairs")
    ap.add_argument("--fps-redraws", type=int, default=0,
                    help="also film each rate of the fps pairs again with new noise, this many times")
    ap.add_argument("--raw", action="store_true",
                    help="the estimators alone: no input cleaning, no working frame rate, no second pass")
    ap.add_argument("--one-pass", action="store_true",
                    help="no second solve without the points the first left unexplained")
    ap.add_argument("--background", action="store_true",
                    help="every case also tracks 8-16 static background points (the camera from the scene)")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    clips = list(args.clips) + ["builtin:walk", "builtin:run"]
    clips = [c for c in clips if args.half == "both" or half_of(c) == args.half]
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    rows = []
    t0 = time.time()
    for clip in clips:
        cases = [draw_case(clip, "target", d) for d in range(args.draws)]
        cases += [draw_case(clip, "broad", d) for d in range(args.broad)]
        if args.background:
            for c in cases:
                c["static_points"] = int(_case_rng(clip, c["case"] + "-background", c["draw"]).integers(8, 17))
        for c in cases:
            for r in run_case(c, methods, args.max_s, args.raw, second_pass=not args.one_pass):
                r["half"] = half_of(clip)
                rows.append(r)
                if "error" in r:
                    print(f"{os.path.basename(clip):<44} {r['case']:<6} {r['method']:<5} error: {r['error']}",
                          flush=True)
                    continue
                print(f"{os.path.basename(clip):<44} {r['half']:<6} {r['case']:<6} {r['method']:<5} "
                      f"{r['operator']:<8} {r['fps']:5.0f} fps {r['focal_mm']:4.0f} mm {r['noise_px']:.1f} px "
                      f"det {'on ' if r['detector'] else 'off'} | {r['mean_pp']:.2f}/{r['max_pp']:.2f} pp "
                      f"rot {r['rotation_deg']:.2f} mpjpe {'-' if r['mpjpe_mm'] is None else round(r['mpjpe_mm'])}"
                      f" {'BAD ' if is_bad(r) else ''}flags {','.join(r['flags']) or '-'} {r['seconds']:.1f}s",
                      flush=True)
    fps_rows = [] if args.no_fps else fps_pairs(clips, min(args.max_s, 20.0), redraws=args.fps_redraws)
    summarize(rows)
    for h in sorted({r["half"] for r in fps_rows}):
        fr = [r for r in fps_rows if r["half"] == h]
        print(f"fps pairs {h}: {len(fr)} clips, proportions differ by median "
              f"{_q([r['diff_mean_pp'] for r in fr], .5):.3f} / max {max(r['diff_mean_pp'] for r in fr):.3f} pp, "
              f"rotation error by median {_q([r['diff_rotation_deg'] for r in fr], .5):.3f} / max "
              f"{max(r['diff_rotation_deg'] for r in fr):.3f} deg")
        if args.fps_redraws:
            pp = [a[0] for r in fr for v in r["redraw"].values() for a in v]
            deg = [a[1] for r in fr for v in r["redraw"].values() for a in v]
            print(f"  the same rate with new noise alone: {_q(pp, .5):.3f} / max {max(pp):.3f} pp, "
                  f"{_q(deg, .5):.3f} / max {max(deg):.3f} deg")
    print(f"total {time.time() - t0:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"rows": rows, "fps": fps_rows}, fh, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
