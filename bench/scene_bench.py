"""Camera-from-the-scene benchmark: handheld footage with static background tracks.

Every clip is filmed in ``--draws`` randomized cases: a handheld operator, a lens drawn from 18-85 mm
that the estimator is not told, 8-16 static points (:mod:`core.synthetic.footage_sim.scene_points`), 1 px noise,
30 fps, a random azimuth.  Each case is estimated three ways:

* ``scene``: :func:`core.scene_camera.solve_scene_camera` alone (camera only);
* ``joint+scene``: the default method with the background tracks;
* ``joint``: the default method with the person alone (the tracks' static block dropped).

``--oracle`` adds a bound, not a method: each frame's rotation from its own background points with
their true directions and the true focal length (Kabsch on the viewing rays), frame 0 the identity as
for the methods. It is what one frame's points say about its camera; only a prior across frames can
do better.

Clips are split into a tuning and a report half by the SHA-1 of their file name, as in
``bench/robust_bench.py``; quote ``report``.

    python bench/scene_bench.py ../shared/data/bvh/*.bvh [--half report] [--draws 2] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation.evaluate import score  # noqa: E402
from core.evaluation.metrics import rotation_errors_deg  # noqa: E402
from core.scene_camera import solve_scene_camera  # noqa: E402
from core.synthetic.footage_sim import HandheldOperator  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402


def draw(clip: str, k: int) -> dict:
    rng = _case_rng(clip, "scene", k)
    return {"clip": clip, "draw": k, "seed": int(rng.integers(1 << 30)),
            "focal_mm": float(np.exp(rng.uniform(np.log(18.0), np.log(85.0)))),
            "view_offset_deg": float(rng.uniform(-90.0, 90.0)), "points": int(rng.integers(8, 17))}


def camera_scores(rotvec_deg, focal_mm, truth) -> dict:
    rot = rotation_errors_deg(rotvec_deg, truth.rotvec_deg)
    fe = 100.0 * np.abs(np.asarray(focal_mm) / truth.focal_mm - 1.0)
    f = np.asarray(focal_mm, dtype=float)
    ratio = 100.0 * np.abs((f / f[0]) / (truth.focal_mm / truth.focal_mm[0]) - 1.0)   # zoom, whatever the lens
    return {"rotation_deg": float(np.median(rot)), "rotation_p95_deg": float(np.quantile(rot, 0.95)),
            "focal_median_pct": float(np.median(fe)), "focal_max_pct": float(fe.max()), "focal0_pct": float(fe[0]),
            "zoom_ratio_max_pct": float(ratio.max())}


def oracle_rotvecs(tracks, truth) -> np.ndarray:
    """(F, 3) degrees: each frame's rotation from its background points alone, given their true
    directions and the true focal length, relative to frame 0's found the same way (NaN with fewer
    than 3 points)."""
    from scipy.spatial.transform import Rotation

    from core.camera import mm_per_pixel

    pts = np.asarray(truth.generator["static_points_cam0"], dtype=float)
    dirs = pts / np.linalg.norm(pts, axis=1, keepdims=True)
    w, h = tracks.image_size
    fpx = np.asarray(truth.focal_mm) / mm_per_pixel(tracks.image_size)
    found = []
    for i in range(tracks.n_frames):
        ok = np.isfinite(tracks.static.xy[i]).all(axis=1)
        if ok.sum() < 3:
            found.append(None)
            continue
        rays = np.c_[(tracks.static.xy[i, ok] - [w / 2.0, h / 2.0]) / fpx[i], np.ones(ok.sum())]
        found.append(Rotation.align_vectors(rays / np.linalg.norm(rays, axis=1, keepdims=True), dirs[ok])[0])
    if found[0] is None:
        return np.full((tracks.n_frames, 3), np.nan)
    inv0 = found[0].inv()
    return np.array([np.degrees((r * inv0).as_rotvec()) if r is not None else [np.nan] * 3 for r in found])


def run(c: dict, max_s: float, scene_only: bool = False, paper: bool = False, oracle: bool = False) -> list[dict]:
    motion = load_motion(c["clip"], fps=30.0, max_frames=int(round(max_s * 30.0)))
    tracks, truth = synthesize(motion, focal_mm=c["focal_mm"], noise_px=1.0, seed=c["seed"],
                               view_offset_deg=c["view_offset_deg"], operator=HandheldOperator(),
                               static_points=c["points"])
    rows = []
    t0 = time.perf_counter()
    sc = solve_scene_camera(tracks)
    sec = time.perf_counter() - t0
    if sc is None:
        rows.append({**c, "method": "scene", "error": "no scene camera"})
    else:
        rows.append({**c, "method": "scene", "seconds": sec, **camera_scores(sc.rotvec_deg, sc.focal_mm, truth),
                     "determined": sc.focal_determined, "turn_deg": sc.turn_deg, "used": sc.usable,
                     "parallax_px": sc.parallax_px})
    if oracle:
        rv = oracle_rotvecs(tracks, truth)
        ok = np.isfinite(rv).all(axis=1)
        rot = rotation_errors_deg(rv[ok], truth.rotvec_deg[ok])
        rows.append({**c, "method": "oracle", "seconds": 0.0, "rotation_deg": float(np.median(rot)),
                     "rotation_p95_deg": float(np.quantile(rot, 0.95)), "focal_median_pct": 0.0,
                     "focal_max_pct": 0.0, "focal0_pct": 0.0, "zoom_ratio_max_pct": 0.0, "determined": True})
    runs = [] if scene_only else [("joint+scene", "joint", True), ("joint", "joint", False)]
    if paper:
        runs += [("paper+scene", "paper", True), ("paper", "paper", False)]
    for name, method, background in runs:
        t0 = time.perf_counter()
        est = estimate(tracks, method, background=background)
        sec = time.perf_counter() - t0
        s = score(est, truth)
        rv = np.array([f.rotvec_deg for f in est.frames])
        fm = np.array([f.focal_mm for f in est.frames])
        rows.append({**c, "method": name, "seconds": sec, **camera_scores(rv, fm, truth),
                     "determined": est.diagnostics.get("focal_determined"),
                     "turn_deg": (sc.turn_deg if sc is not None else None),
                     "mean_pp": s["proportions"]["mean_abs"], "max_pp": s["proportions"]["max_abs"],
                     "mpjpe_frame_mm": s.get("mpjpe_frame_mm"), "mpjpe_clip_mm": s.get("mpjpe_clip_mm"),
                     "stance": s["stance_accuracy"],
                     "flags": [f["code"] for f in est.diagnostics["self_check"]["flags"]]})
    return rows


def _m(rows, key, q=0.5):
    v = [r[key] for r in rows if r.get(key) is not None and np.isfinite(r[key])]
    return float(np.quantile(v, q)) if v else float("nan")


def summarize(rows: list[dict], out=sys.stdout) -> None:
    print("\n| half | method | cases | rotation deg, median clip / p95 clip | focal % per frame, median clip / "
          "worst frame | zoom ratio % worst frame, median clip / worst | f0 % where determined (n) / turn >= 10 deg "
          "undetermined | proportions mean / max pp (mean over cases) | 3D per frame / whole clip mm (median) | "
          "stance % | flagged | sec median |", file=out)
    print("|---|---|---|---|---|---|---|---|---|---|---|---|", file=out)
    for h in sorted({r["half"] for r in rows}):
        for m in ("oracle", "scene", "joint+scene", "joint", "paper+scene", "paper"):
            rs = [r for r in rows if r["half"] == h and r["method"] == m and "error" not in r]
            if not rs:
                continue
            det = [r for r in rs if r.get("determined")]
            big_undet = sum(1 for r in rs if not r.get("determined") and (r.get("turn_deg") or 0) >= 10)
            f0 = f"{_m(det, 'focal0_pct'):.2f} / max {_m(det, 'focal0_pct', 1.0):.2f} ({len(det)})" if det else "-"
            pp = "-"
            if "mean_pp" in rs[0]:
                pp = f"{np.mean([r['mean_pp'] for r in rs]):.2f} / {np.mean([r['max_pp'] for r in rs]):.2f}"
            mp = "-"
            if any(r.get("mpjpe_frame_mm") is not None for r in rs):
                mp = f"{_m(rs, 'mpjpe_frame_mm'):.0f} / {_m(rs, 'mpjpe_clip_mm'):.0f}"
            st = f"{100 * _m(rs, 'stance'):.1f}" if "stance" in rs[0] else "-"
            fl = f"{sum(1 for r in rs if r.get('flags'))}/{len(rs)}" if "flags" in rs[0] else "-"
            print(f"| {h} | {m} | {len(rs)} | {_m(rs, 'rotation_deg'):.3f} / {_m(rs, 'rotation_deg', .95):.3f} | "
                  f"{_m(rs, 'focal_median_pct'):.2f} / {_m(rs, 'focal_max_pct', 1.0):.2f} | "
                  f"{_m(rs, 'zoom_ratio_max_pct'):.2f} / {_m(rs, 'zoom_ratio_max_pct', 1.0):.2f} | "
                  f"{f0} / {big_undet} | "
                  f"{pp} | {mp} | {st} | {fl} | {_m(rs, 'seconds'):.1f} |", file=out)
    for r in rows:
        if "error" in r:
            print(f"error: {os.path.basename(r['clip'])} {r['method']}: {r['error']}", file=out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--draws", type=int, default=2)
    ap.add_argument("--max-s", type=float, default=30.0, help="seconds of each clip at most (default 30)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--scene-only", action="store_true", help="the scene camera alone (no estimates)")
    ap.add_argument("--paper", action="store_true", help="also the paper's method with and without the background")
    ap.add_argument("--oracle", action="store_true",
                    help="also the bound: each frame's rotation from its points' true directions and focal length")
    args = ap.parse_args(argv)
    clips = list(args.clips) + ["builtin:walk", "builtin:run"]
    rows = []
    for clip in clips:
        h = half_of(clip)
        if args.half != "both" and h != args.half:
            continue
        for k in range(args.draws):
            c = draw(clip, k)
            for r in run(c, args.max_s, args.scene_only, args.paper, args.oracle):
                r["half"] = h
                rows.append(r)
                if "error" not in r:
                    extra = f" {r['mean_pp']:.2f}/{r['max_pp']:.2f} pp" if "mean_pp" in r else ""
                    print(f"{os.path.basename(clip)} #{k} {r['method']}: rot {r['rotation_deg']:.3f} deg, "
                          f"focal {r['focal_median_pct']:.2f}/{r['focal_max_pct']:.2f} %, f0 {r['focal0_pct']:.2f} % "
                          f"det {r['determined']}{extra} {r['seconds']:.1f} s", flush=True)
    summarize(rows)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
