"""Time ``core.estimate.estimate`` for every available method on 900, 3,000 and 10,000 frames.

Inputs are synthetic tracks of the built-in walk, extended to the wanted length
by repeating its gait cycles to and fro (see :func:`long_walk`; the camera schedule
is drawn for the full length), at 30 fps, 720x480, 1 px noise, pan/tilt/zoom spells.
Each run is a fresh process, so its peak RSS is its own.

    python bench/bench_estimate.py [--frames 900,3000,10000] [--methods paper,joint]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import resource
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from core.estimate import METHODS, estimate  # noqa: E402
from core.synthetic.motion import Motion, load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402


def long_walk(n_frames: int, lap_s: float = 8.0) -> Motion:
    """The built-in walk made ``n_frames`` long, walking to and fro so the figure stays near the camera.

    Whole gait cycles are repeated, each moved on by one stride, for a lap of about
    ``lap_s`` seconds; the next lap is the same lap played backwards (the figure walks
    back with its feet planted exactly as before), and so on.
    """
    base = load_motion("builtin:walk", fps=30.0)
    joints, contacts = base.joints, base.contacts
    # One gait cycle = between two successive left touch-downs.
    starts = np.flatnonzero(np.diff(contacts[:, 0].astype(int)) == 1) + 1
    a, b = (int(starts[0]), int(starts[1])) if starts.size >= 2 else (0, base.n_frames)
    cycle, cyc_contacts = joints[a:b], contacts[a:b]
    stride = joints[b, 0] - joints[a, 0]
    stride[1] = 0.0
    per_lap = max(1, int(round(lap_s * 30.0 / len(cycle))))
    lap = np.concatenate([cycle + k * stride for k in range(per_lap)])
    lap_contacts = np.concatenate([cyc_contacts] * per_lap)
    parts, cparts, total, forward = [], [], 0, True
    while total < n_frames:
        parts.append(lap if forward else lap[::-1])
        cparts.append(lap_contacts if forward else lap_contacts[::-1])
        total += len(lap)
        forward = not forward
    return Motion(f"walk x{n_frames}", 30.0, np.concatenate(parts)[:n_frames], base.class_lengths,
                  np.concatenate(cparts)[:n_frames], dict(base.meta))


def _timeout(signum, frame):
    raise TimeoutError("gave up (--max-seconds)")


def run_one(n_frames: int, method: str, max_seconds: int, static_points: int = 0,
            handheld: bool = False, lifter: bool = True) -> tuple[float, str, float, float]:
    """One timed estimate, meant to run in a fresh process: (wall seconds, note, peak RSS in MB, CPU seconds).

    CPU time is reported beside wall time because the development machine's host is shared: wall
    time there swings by up to 2x between identical runs, CPU time much less.

    A fresh process per run makes the peak RSS this run's own (``ru_maxrss`` never goes down, so
    in one process every later row would inherit the largest earlier peak).  The tracks are made
    in the child, untimed; the RSS includes them and the interpreter, as a real ``python -m core
    estimate`` run would.
    """
    from core.joint_solve import pipeline
    from core.synthetic.footage_sim import HandheldOperator

    pipeline.USE_POSE_LIFTER = lifter

    tracks, truth = synthesize(long_walk(n_frames), noise_px=1.0, seed=0, static_points=static_points,
                               operator=HandheldOperator() if handheld else None)
    signal.signal(signal.SIGALRM, _timeout)
    signal.alarm(max_seconds)
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        est = estimate(tracks, method)
        err = np.abs(est.proportions_vector() - truth.proportions).mean() * 100
        note = f"mean proportion error {err:.2f} pp"
    except Exception as exc:  # report and continue with the other methods
        note = f"FAILED {type(exc).__name__}: {str(exc)[:80]}"
    finally:
        signal.alarm(0)
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    return dt, note, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, cpu


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", default="900,3000,10000")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--max-seconds", type=int, default=600, help="give up on one run after this long")
    ap.add_argument("--static-points", type=int, default=0, help="background points filmed too (default 0)")
    ap.add_argument("--handheld", action="store_true", help="a handheld operator instead of the paper's schedule")
    ap.add_argument("--no-lifter", action="store_true", help="the joint solve without the pose lifter's cue")
    args = ap.parse_args(argv)
    sizes = [int(v) for v in args.frames.split(",")]
    methods = [m for m in args.methods.split(",") if m]
    print(f"{'method':<8} {'frames':>7} {'seconds':>9} {'CPU s':>7} {'ms/frame':>9} {'peak RSS MB':>12}  result")
    spawn = multiprocessing.get_context("spawn")
    for n in sizes:
        for m in methods:
            with spawn.Pool(1) as pool:
                dt, note, rss, cpu = pool.apply(run_one, (n, m, args.max_seconds, args.static_points,
                                                          args.handheld, not args.no_lifter))
            print(f"{m:<8} {n:>7} {dt:9.2f} {cpu:7.2f} {dt / n * 1000:9.2f} {rss:12.0f}  {note}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
