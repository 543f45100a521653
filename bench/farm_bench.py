"""Many shots on one machine: a folder of 8 built-in 300-frame shots with ``--workers 2`` against one after
another (``--workers 1``), both through ``batch.py --folder``.

The shots are the built-in walk (300 frames) filmed by the paper's virtual camera with a different seed
each (camera moves and 2D noise), written as tracks files.  Reported: the wall time of each run, their
ratio (parallel / one after another), the CPU time, and the peak memory of each shot's process (measured
by the kernel, kept in each shot's status record).  On 2 idle cores the ideal ratio is 0.5; each shot also
starts its own Python with bpy, which the two workers overlap as well.  The load average is printed with
each run: when other programs keep the cores busy, a second worker has no free core to use and the ratio
says more about them than about the folder run.

Run:  python bench/farm_bench.py [--shots 8] [--frames 300] [--workers 2] [--repeats 1]
(with the Python that has the PyPI ``bpy`` module, e.g. .venvs/bpy-5.0.1/bin/python).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--shots", type=int, default=8)
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--repeats", type=int, default=1, help="pairs of runs, one after another then in parallel")
    p.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    return p.parse_args()


def make_shots(folder: str, n: int, frames: int) -> None:
    sys.path.insert(0, ROOT)
    from core.synthetic.motion import load_motion
    from core.synthetic.synth import synthesize
    from core.tracks import write_tracks_json

    motion = load_motion("builtin:walk", max_frames=frames)
    if motion.n_frames < frames:
        raise SystemExit(f"the built-in walk has {motion.n_frames} frames, fewer than --frames {frames}")
    for seed in range(n):
        tracks, _ = synthesize(motion, seed=seed)
        write_tracks_json(tracks, os.path.join(folder, f"walk_{seed:02d}.json"))


def run_folder(shots: str, out: str, workers: int) -> dict:
    """One folder run in a fresh output folder: wall and CPU seconds, and each shot's peak memory."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "batch.py"), "--folder", shots, "--output-dir", out,
                           "--workers", str(workers)], capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"the folder run failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    peaks, seconds = [], []
    for name in sorted(os.listdir(out)):
        status = os.path.join(out, name, f"{name}.status.json")
        if os.path.isfile(status):
            with open(status, encoding="utf-8") as fh:
                doc = json.load(fh)
            peaks.append(doc["peak_rss_mb"])
            seconds.append(doc["seconds"])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"workers": workers, "wall_s": wall, "cpu_s": cpu, "shot_s": seconds, "peak_rss_mb": peaks}


def main() -> int:
    args = _args()
    runs = {1: [], args.workers: []}
    with tempfile.TemporaryDirectory(prefix="farm_bench_") as tmp:
        shots = os.path.join(tmp, "shots")
        os.mkdir(shots)
        make_shots(shots, args.shots, args.frames)
        print(f"{args.shots} shots of the built-in walk, {args.frames} frames each; {os.cpu_count()} cores; "
              f"Python {sys.version.split()[0]}; load average before: {os.getloadavg()[0]:.1f}", flush=True)
        for k in range(args.repeats):
            for workers in (1, args.workers):
                run = run_folder(shots, os.path.join(tmp, f"out_{k}_{workers}"), workers)
                runs[workers].append(run)
                print(f"  --workers {workers}: {run['wall_s']:.1f} s wall, {run['cpu_s']:.1f} s CPU "
                      f"(load average after: {os.getloadavg()[0]:.1f})", flush=True)
    one, par = runs[1], runs[args.workers]
    wall1 = statistics.median(r["wall_s"] for r in one)
    wall2 = statistics.median(r["wall_s"] for r in par)
    ratios = [p["wall_s"] / o["wall_s"] for o, p in zip(one, par)]
    print()
    print("| run | wall s | CPU s | median s per shot | peak MB per shot process (median / max) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for label, rs in (("one after another (--workers 1)", one), (f"--workers {args.workers}", par)):
        peaks = [p for r in rs for p in r["peak_rss_mb"]]
        shot_s = [s for r in rs for s in r["shot_s"]]
        print(f"| {label} | {statistics.median(r['wall_s'] for r in rs):.1f} | "
              f"{statistics.median(r['cpu_s'] for r in rs):.1f} | {statistics.median(shot_s):.1f} | "
              f"{statistics.median(peaks):.0f} / {max(peaks):.0f} |")
    print(f"\nratio (--workers {args.workers} / one after another): {statistics.median(ratios):.2f}"
          + (f" (per pair: {', '.join(f'{r:.2f}' for r in ratios)})" if len(ratios) > 1 else "")
          + f"; wall {wall2:.1f} s against {wall1:.1f} s")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump({"shots": args.shots, "frames": args.frames, "runs": runs, "ratios": ratios}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
