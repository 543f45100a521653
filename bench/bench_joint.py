"""Benchmark of the "joint" method against synthetic truth (its speed and memory targets).

    python bench/bench_joint.py [--motion builtin:walk|PATH.bvh ...] [--frames N] [--noise PX]
                                [--hint] [--methods joint,paper] [--dropout F] [--occlusion S]
    python bench/bench_joint.py --targets      # speed/memory targets, see below

Prints one line per clip with every target metric (core.evaluation.evaluate.score), the
time, the load average at the start, and the peak memory (ru_maxrss).

``--targets`` runs the two resource checks (900 frames <= 10 s, 10,000 frames <= 2 GB), each in a fresh child
process so its peak memory is its own: a 900-frame clip (the built-in walk
to and fro, :func:`bench_estimate.long_walk`) must be estimated in <= 10 s,
and a 10,000-frame clip must complete within 2 GB (peak RSS of the whole
process, synthesis included).  It prints the measured time and memory and
PASS / FAIL.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))        # bench_estimate, for --targets

from core.estimate import estimate  # noqa: E402
from core.evaluation.evaluate import score  # noqa: E402
from core.synthetic.motion import Motion, load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402


def _ping_pong(motion: Motion, frames: int) -> Motion:
    """Repeat a motion forwards, backwards, forwards... to reach ``frames`` (long-clip benchmarks only)."""
    parts, cparts, k = [], [], 0
    while sum(len(p) for p in parts) < frames:
        parts.append(motion.joints if k % 2 == 0 else motion.joints[::-1])
        cparts.append(motion.contacts if k % 2 == 0 else motion.contacts[::-1])
        k += 1
    return Motion(motion.name + "-long", motion.fps, np.concatenate(parts)[:frames], motion.class_lengths,
                  np.concatenate(cparts)[:frames], dict(motion.meta))


def run_one(source: str, frames: int | None, noise: float, hint: bool, method: str, dropout: float,
            occlusion: float, seed: int, kinds, fps: float, continuous: bool, long: int | None,
            synth_focal: float = 50.0) -> dict:
    motion = load_motion(source, max_frames=frames, fps=fps)
    if long:
        motion = _ping_pong(motion, long)
    tracks, truth = synthesize(motion, kinds=kinds, noise_px=noise, dropout=dropout, occlusion_s=occlusion,
                               seed=seed, continuous=continuous, focal_mm=synth_focal)
    t0 = time.perf_counter()
    est = estimate(tracks, method, focal_mm=float(truth.focal_mm[0]) if hint else None)
    seconds = time.perf_counter() - t0
    sc = score(est, truth)
    sc["seconds"] = seconds
    sc["frames"] = truth.n_frames
    return sc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--motion", nargs="*", default=["builtin:walk"])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--noise", type=float, default=1.0)
    ap.add_argument("--dropout", type=float, default=0.0)
    ap.add_argument("--occlusion", type=float, default=0.0)
    ap.add_argument("--hint", action="store_true", help="give the true frame-0 focal length as a hint")
    ap.add_argument("--method", default="joint")
    ap.add_argument("--kinds", default="pan,tilt,zoom")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--fps", type=float, default=30.0, help="resample the motion to this rate")
    ap.add_argument("--continuous", action="store_true", help="pan, tilt and zoom at the same time")
    ap.add_argument("--long", type=int, default=None, help="ping-pong the motion to this many frames")
    ap.add_argument("--synth-focal", type=float, default=50.0, help="true frame-0 focal length of the clip (mm)")
    ap.add_argument("--methods", default=None, help="comma list, e.g. joint,paper (overrides --method)")
    ap.add_argument("--targets", action="store_true", help="check the 900-frame time and 10,000-frame memory")
    args = ap.parse_args(argv)
    if args.targets:
        return check_targets()
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores shared)")
    hdr = ("clip", "method", "frames", "prop mean pp", "prop max pp", "f0 err %", "zoom f err %", "rot med deg",
           "mpjpe frame mm", "mpjpe clip mm", "stance %", "f det", "time s")
    print(" | ".join(hdr))
    methods = args.methods.split(",") if args.methods else [args.method]
    for src, method in [(s, m) for s in args.motion for m in methods]:
        sc = run_one(src, args.frames, args.noise, args.hint, method, args.dropout, args.occlusion,
                     args.seed, tuple(args.kinds.split(",")), args.fps, args.continuous, args.long,
                     args.synth_focal)
        p = sc["proportions"]
        name = Path(src).stem if not src.startswith("builtin:") else src
        row = (name, method, sc["frames"], f"{p['mean_abs']:.2f}",
               f"{p['max_abs']:.2f}", f"{sc['focal0_error_pct']:+.2f}", f"{sc['zoom_focal_error_pct']:.2f}",
               f"{sc['rotation_error_deg']:.3f}", f"{sc.get('mpjpe_frame_mm', float('nan')):.1f}",
               f"{sc.get('mpjpe_clip_mm', float('nan')):.1f}", f"{sc['stance_accuracy'] * 100:.1f}",
               sc["focal_determined"], f"{sc['seconds']:.2f}")
        print(" | ".join(str(v) for v in row), flush=True)
    print(f"peak memory (ru_maxrss): {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    return 0


def check_targets() -> int:
    """The resource targets, each in its own process (see module docstring).

    The run itself is ``bench_estimate.run_one`` (the built-in walk to and fro, timed in a fresh
    process, peak RSS of that process), so both benchmarks measure one thing one way.
    """
    import multiprocessing

    from bench_estimate import run_one as timed_run

    ok_all = True
    spawn = multiprocessing.get_context("spawn")
    for frames, max_s, max_mb in ((900, 10.0, None), (10000, None, 2048.0)):
        print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores shared)", flush=True)
        with spawn.Pool(1) as pool:
            seconds, note, mb, cpu = pool.apply(timed_run, (frames, "joint", 600))
        ok = not note.startswith("FAILED") and (max_s is None or seconds <= max_s) and (max_mb is None or mb <= max_mb)
        ok_all &= ok
        limit = f"<= {max_s:.0f} s" if max_s else f"<= {max_mb:.0f} MB"
        print(f"{frames} frames: {seconds:.1f} s (CPU {cpu:.1f} s), peak RSS {mb:.0f} MB, {note} (target {limit}): "
              f"{'PASS' if ok else 'FAIL'}", flush=True)
    return 0 if ok_all else 1

if __name__ == "__main__":
    raise SystemExit(main())
