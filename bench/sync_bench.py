"""Synchronisation benchmark: does :func:`core.multiview.sync.frame_offset` say so when it may be wrong?

Two still cameras film one motion (:mod:`core.multiview.synth`); the second view starts a random whole
number of frames (up to 1.5 s either way) before or after the first.  Periodic motions (walks, a jog,
skipping) repeat every step, so an offset a cycle away can fit almost as well as the true one.  Per
case: the offset chosen, the true one, every offset judged and its fit.  The margin that calls an
answer ambiguous (``AMBIGUITY_MARGIN``) is chosen on the tune half of the clips and reported on the
other: target, a warning in every case where the wrong offset is chosen, with few false alarms.

Cases per clip: people of ordinary size (cameras 4.5 m beyond the motion's reach, 1280 x 720) and
small ones (12 m, 960 x 540: some 90-200 px tall), each with 1 px noise alone and with a detector's
errors (:data:`core.synthetic.footage_sim.detector.TYPICAL`).  With ``--steady`` the periodic clips are made
perfectly periodic (their cycle repeated, moved on by its travel each time), the hardest case.  With
``--static`` the cases the joints alone got wrong or called ambiguous are run again with eight still
scene points both views track under one name.

    python bench/sync_bench.py ../shared/data/bvh/*.bvh builtin:walk --json out/sync.json
    python bench/sync_bench.py ../shared/data/bvh/*.bvh builtin:walk --steady --json out/sync_steady.json
    python bench/sync_bench.py --from-json out/sync.json            # the tables again, no sync run
    python bench/sync_bench.py --from-json out/sync.json --static --clip-dir ../shared/data/bvh --json out/s2.json
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

from core.multiview.sync import SEPARATION_FRAMES, frame_offset  # noqa: E402
from core.multiview.synth import film_views, ring_cameras, steady_repeat  # noqa: E402
from core.synthetic.footage_sim.detector import TYPICAL  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.tracks import StaticTracks  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from robust_bench import half_of  # noqa: E402

VARIANTS = [{"small": False, "det": False}, {"small": False, "det": True},
            {"small": True, "det": False}, {"small": True, "det": True}]
MARGINS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.75, 1.0)
FPS = 30.0
REACH_S = 1.5


def _rng(clip: str, k: int) -> np.random.Generator:
    digest = hashlib.sha1(f"{os.path.basename(clip)}|sync|{k}".encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def scene_points(motion, cams, n: int, rng) -> list[StaticTracks]:
    """``n`` still points around the motion at heights 0-2.5 m (not on one plane: points of one plane, a
    floor alone, leave the epipolar geometry free), tracked in every view under the same names."""
    joints = np.asarray(motion.joints, dtype=float)
    middle = np.nanmean(joints.reshape(-1, 3), axis=0)
    floor = float(np.nanmin(joints[..., 1]))
    pts = middle + np.c_[rng.uniform(-3, 3, n), np.zeros(n), rng.uniform(-3, 3, n)]
    pts[:, 1] = floor + rng.uniform(0.0, 2.5, n)
    out = []
    for cam in cams:
        uv = cam.project(pts[None])[0]
        seen = np.isfinite(uv).all(-1) & (uv[:, 0] >= 0) & (uv[:, 0] < cam.image_size[0]) \
            & (uv[:, 1] >= 0) & (uv[:, 1] < cam.image_size[1])
        xy = np.where(seen[:, None], uv, np.nan)[None].repeat(len(joints), 0)
        xy = xy + rng.normal(0, 1.0, xy.shape)
        out.append(StaticTracks([f"mark_{k}" for k in range(n)], xy, np.isfinite(xy[..., 0]).astype(float)))
    return out


def make_case(clip: str, k: int, static: bool = False, steady: bool = False):
    """(view 1, view 2, true offset, what the case is); None when the clip is too short (or, ``steady``, not
    a repeated movement)."""
    rng = _rng(clip, k)
    var = VARIANTS[k % len(VARIANTS)]
    motion = load_motion(clip, fps=FPS, max_frames=900)
    if steady:
        made = steady_repeat(motion, 600, start=min(60, len(motion.joints) // 4))
        if made is None:
            return None
        motion = made[0]
    n = len(motion.joints)
    reach = int(REACH_S * FPS)
    length = min(n - 2 * reach - 2, 600)
    if length < 90:
        return None
    seed = int(rng.integers(1 << 30))
    cams = ring_cameras(motion, 2, seed=seed, radius_m=12.0 if var["small"] else 4.5,
                        image_size=(960.0, 540.0) if var["small"] else (1280.0, 720.0))
    full = film_views(motion, cams, noise_px=1.0, detector=TYPICAL if var["det"] else None, seed=seed)
    if static:
        full = [v.replaced(static=s) for v, s in zip(full, scene_points(motion, cams, 8, rng))]
    true = int(rng.integers(-reach, reach + 1))
    a = reach + 1

    def cut(view, start):
        st = None if view.static is None else StaticTracks(view.static.names, view.static.xy[start:start + length],
                                                           view.static.conf[start:start + length])
        return view.replaced(xy=view.xy[start:start + length], conf=view.conf[start:start + length], static=st)

    return cut(full[0], a), cut(full[1], a + true), -true, var


def run_case(clip: str, k: int, static: bool = False, steady: bool = False) -> dict | None:
    made = make_case(clip, k, static, steady)
    if made is None:
        return None
    v1, v2, true, var = made
    t = time.perf_counter()
    best, rep = frame_offset(v1, v2, max_s=2.0)
    return {"clip": os.path.basename(clip), "half": half_of(clip), "k": k, **var, "static": static,
            "steady": steady, "true": true,
            "best": best, "error_px": rep["error_px"], "second_offset": rep["second_offset"],
            "second_px": rep["second_px"], "static_points": rep["static_points"],
            "static_refused": rep["static_refused"], "seconds": time.perf_counter() - t}


def ambiguous(r: dict, margin: float) -> bool:
    return r["second_px"] is not None and r["second_px"] <= r["error_px"] * (1.0 + margin)


def wrong(r: dict) -> bool:
    return abs(r["best"] - r["true"]) > SEPARATION_FRAMES


def table(rows: list[dict], title: str) -> None:
    near = sum(1 for r in rows if 0 < abs(r["best"] - r["true"]) <= SEPARATION_FRAMES)
    print(f"\n{title}: {len(rows)} cases, wrong offset chosen in {sum(map(wrong, rows))} "
          f"(off by 1-{SEPARATION_FRAMES} frames: {near})")
    print("| margin | wrong and warned | wrong, no warning | right, warned (false alarms) |")
    print("|---|---|---|---|")
    for m in MARGINS:
        ww = sum(1 for r in rows if wrong(r) and ambiguous(r, m))
        wn = sum(1 for r in rows if wrong(r) and not ambiguous(r, m))
        fa = sum(1 for r in rows if not wrong(r) and ambiguous(r, m))
        print(f"| {m:.2f} | {ww} | {wn} | {fa} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--cases", type=int, default=4, help="cases per clip (they cycle through the variants)")
    ap.add_argument("--steady", action="store_true",
                    help="the clips made perfectly periodic (their cycle repeated, core.multiview.synth.steady_repeat)")
    ap.add_argument("--static", action="store_true", help="run the wrong or ambiguous cases again with scene points")
    ap.add_argument("--margin", type=float, default=None, help="margin for the --static re-run's selection")
    ap.add_argument("--json", default=None, help="write every case here")
    ap.add_argument("--from-json", default=None, help="read the cases from an earlier run instead")
    ap.add_argument("--clip-dir", default=None, help="where the clips of --from-json are (for --static)")
    args = ap.parse_args()
    if args.from_json:
        with open(args.from_json) as fh:
            rows = json.load(fh)
    else:
        rows = []
        for clip in args.clips:
            for k in range(args.cases):
                r = run_case(clip, k, steady=args.steady)
                if r is None:
                    print(f"{os.path.basename(clip)}: too short or not periodic", flush=True)
                    break
                rows.append(r)
                print(f"{r['clip']:44s} {r['half']:6s} {'small' if r['small'] else 'large'} "
                      f"{'det  ' if r['det'] else 'clean'} true {r['true']:+4d} chose {r['best']:+4d} "
                      f"{r['error_px']:.2f} px, next {r['second_offset']} {r['second_px'] or float('nan'):.2f} px "
                      f"({r['seconds']:.1f} s)", flush=True)
    base = [r for r in rows if not r["static"]]
    for half in ("tune", "report"):
        table([r for r in base if r["half"] == half], f"{half} half, joints alone")
    if args.static:
        from core.multiview.sync import AMBIGUITY_MARGIN

        margin = AMBIGUITY_MARGIN if args.margin is None else args.margin
        again = [r for r in base if wrong(r) or ambiguous(r, margin)]
        folder = args.clip_dir or (os.path.dirname(args.clips[0]) if args.clips else ".")
        rows = [r for r in rows if not r["static"]]
        for r in again:
            s = run_case(r["clip"] if r["clip"].startswith("builtin") else os.path.join(folder, r["clip"]), r["k"],
                         static=True, steady=r.get("steady", False))
            rows.append(s)
            print(f"{s['clip']:44s} with scene points: true {s['true']:+4d} chose {s['best']:+4d} "
                  f"{s['error_px']:.2f} px, next {s['second_offset']} {s['second_px'] or float('nan'):.2f} px",
                  flush=True)
        fixed = [r for r in rows if r["static"]]
        bad = [r for r in fixed if wrong(r)]
        warned = sum(ambiguous(r, margin) for r in bad)
        print(f"\nwith eight scene points in both views: {len(fixed)} cases re-run, the points refused in "
              f"{sum(r['static_refused'] for r in fixed)}; wrong {len(bad)} (warned {warned}), right but warned "
              f"{sum(ambiguous(r, margin) for r in fixed if not wrong(r))} (margin {margin:.2f})")
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
