"""Can the fit tell the lens?  Each case solved with the lens told at several multiples of the truth.

A wrong lens is most of what makes planted feet slide on a moving camera ([docs/motion.md](../docs/motion.md)),
and footage often states none.  This bench asks whether the solved motion itself says which lens is
right: every case of ``bench/motion_bench.py`` (the same clips, scenarios, halves and draws) is estimated
as shipped with no lens told and then with the lens told at each ``--factors`` multiple of the true one,
and for each estimate it prints the measures (per-frame error, mirrored frames, planted excess) beside
three readings a lens search could minimise without the truth:

* ``reproj``: the median frame's mean reprojection error, pixels (the fit of the tracks);
* ``lifter``: the mean over frames and limb bones of ``1 - cos`` between the solved bone and the video
  lifter's direction for it, read from the tracks' rays at that lens (how well the pose agrees with the
  lifter);
* ``prior``: the pose prior's mean negative log-likelihood of the solved poses.

The summary gives, per scenario and reading, how often its minimum falls at each factor, and the means of
the measures had each case kept the factor its minimum picks, against the lens assumed (no lens told) and
the true lens (factor 1).  ``--search GRID`` searches as a product would, without the truth: the case
is estimated at each focal length of the grid (mm), the lowest ``--reading`` refined by a parabola in log
focal through it and its neighbours, and the case estimated once more at that lens (the summary's
``searched`` row, with how far each lens is from the truth, in log focal).  ``--free-focal`` adds a row
with no lens told and the focal length left free in the solve: the assumed focal's prior and the paper's
camera prior on the focal length loosened to a sigma of 3 in log focal, so that only the fit holds it.

    python bench/lens_bench.py ../shared/data/bvh/*.bvh --scenario paper,still --half tune --draws 2
    python bench/lens_bench.py ../shared/data/bvh/*.bvh --scenario paper,still,detector --half tune --draws 2 \
        --factors 1 --search 18,24,32,42,56,75,100 --reading lifter
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter, defaultdict

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.motion_bench import (  # noqa: E402
    _arrays,
    add_case_arguments,
    camera_bone_directions,
    chosen_cases,
    film,
    motion_scores,
)
from core.estimate import estimate  # noqa: E402
from core.evaluation.metrics import LIMB_BONES  # noqa: E402
from core.joint_solve import pipeline  # noqa: E402
from core.joint_solve.taylor import unit_rays  # noqa: E402
from core.motion_prior import load_default  # noqa: E402
from core.skeleton import SEGMENTS  # noqa: E402

READINGS = ("reproj", "lifter", "prior")
MEASURES = (("mpjpe_frame_mm", "P-MPJPE mm", ".1f"), ("mirrored_pct", "mirrored %", ".1f"),
            ("planted_excess_mm_s", "planted excess mm/s", ".0f"))
_LIMB_SEGMENTS = [SEGMENTS.index(b) for b in LIMB_BONES]
#: the sigma (log focal) the ``--free-focal`` row loosens the focal's priors to
FREE_SIGMA = 3.0


def readings(joints: np.ndarray, rotvec_deg: np.ndarray, focal_mm: np.ndarray, tracks, reproj_px: float) -> dict:
    """The three readings of one estimate (module docstring)."""
    unit = camera_bone_directions(joints, rotvec_deg)[:, _LIMB_SEGMENTS]
    cue = pipeline.lifter_cue(unit_rays(tracks.xy, np.asarray(focal_mm, dtype=float)[:, None], tracks.image_size),
                              tracks.fps)
    lifter = float(np.nanmean(1.0 - np.sum(unit * cue[:, _LIMB_SEGMENTS], axis=-1)))
    prior = float(-np.nanmean(load_default().log_likelihood(joints)))
    return {"reproj": reproj_px, "lifter": lifter, "prior": prior}


def solve(tracks, truth, focal_mm: float | None) -> dict:
    est = estimate(tracks, "joint", **({} if focal_mm is None else {"focal_mm": focal_mm}))
    j, rv, fm = _arrays(est)
    scores = motion_scores(j, rv, fm, tracks, truth)
    return {**{k: scores[k] for k, _, _ in MEASURES}, "focal_mm": float(np.median(fm)),
            **readings(j, rv, fm, tracks, scores["reproj_px"])}


def free_focal_solve(tracks, truth) -> dict:
    """No lens told, the focal's priors loosened to :data:`FREE_SIGMA` (module docstring)."""
    saved = (pipeline.UNDETERMINED_FOCAL_SIGMA, pipeline.PAPER_CAMERA_SIGMA, pipeline.STILL_CAMERA_SIGMA)
    pipeline.UNDETERMINED_FOCAL_SIGMA = FREE_SIGMA
    pipeline.PAPER_CAMERA_SIGMA = (saved[1][0], FREE_SIGMA)
    pipeline.STILL_CAMERA_SIGMA = (saved[2][0], FREE_SIGMA)
    try:
        return solve(tracks, truth, None)
    finally:
        pipeline.UNDETERMINED_FOCAL_SIGMA, pipeline.PAPER_CAMERA_SIGMA, pipeline.STILL_CAMERA_SIGMA = saved


def searched_focal(grid_mm: list[float], values: list[float]) -> float:
    """The focal length (mm) where ``values`` (one per grid focal) are lowest: the lowest grid point, refined
    by a parabola in log focal through it and its two neighbours when it has both and they curve upwards."""
    v = np.asarray(values, dtype=float)
    i = int(np.argmin(v))
    if not 0 < i < len(v) - 1:
        return float(grid_mm[i])
    curve = v[i - 1] - 2.0 * v[i] + v[i + 1]
    if not curve > 0:
        return float(grid_mm[i])
    lg = np.log(np.asarray(grid_mm, dtype=float))
    step = 0.5 * (v[i - 1] - v[i + 1]) / curve                    # in grid steps, within (-0.5, 0.5)
    return float(np.exp(lg[i] + step * (lg[i + 1] - lg[i] if step > 0 else lg[i] - lg[i - 1])))


def _row(label: str, r: dict) -> str:
    return (f"  {label:>9s}: focal {r['focal_mm']:5.1f} mm | "
            + " ".join(f"{h} {format(r[k], s)}" for k, h, s in MEASURES)
            + f" | reproj {r['reproj']:.3f} lifter {r['lifter']:.5f} prior {r['prior']:.2f}")


def summarize(results: list[dict], factors: list[float]) -> None:
    by_scenario = defaultdict(list)
    for res in results:
        by_scenario[res["case"]["scenario"]].append(res)
    for scen, rs in by_scenario.items():
        print(f"\n{scen}: {len(rs)} cases")
        head = ["lens", *[h for _, h, _ in MEASURES]]
        print("| " + " | ".join(head) + " |")
        print("|---" * len(head) + "|")

        def line(label, picked):
            cells = [format(float(np.mean([p[k] for p in picked])), s) for k, _, s in MEASURES]
            print(f"| {label} | " + " | ".join(cells) + " |")

        line("assumed (none told)", [r["assumed"] for r in rs])
        line("true (factor 1)", [r["told"][1.0] for r in rs if 1.0 in r["told"]])
        for name in READINGS if len(factors) > 1 else ():
            picks = [min(r["told"].items(), key=lambda kv: kv[1][name]) for r in rs]
            line(f"picked by {name}", [p[1] for p in picks])
            counts = Counter(k for k, _ in picks)
            print(f"    {name}: minimum at " + ", ".join(f"{k:g}x {counts.get(k, 0)}" for k in factors))
        if all("searched" in r for r in rs):
            line(f"searched by {rs[0]['reading']}", [r["searched"] for r in rs])
            off = np.array([abs(np.log(r["searched"]["focal_mm"] / r["case"]["focal_mm"])) for r in rs])
            assumed = np.array([abs(np.log(r["assumed"]["focal_mm"] / r["case"]["focal_mm"])) for r in rs])
            ratio = np.array([r["searched"]["focal_mm"] / r["case"]["focal_mm"] for r in rs])
            print(f"    searched lens over the true: median {np.median(ratio):.2f}, "
                  f"{ratio.min():.2f}-{ratio.max():.2f}; |log| mean {off.mean():.2f} against the assumed lens' "
                  f"{assumed.mean():.2f}")
        if all("free" in r for r in rs):
            line("free focal", [r["free"] for r in rs])
            ratio = [r["free"]["focal_mm"] / r["case"]["focal_mm"] for r in rs]
            print(f"    free focal over the true: median {np.median(ratio):.2f}, {min(ratio):.2f}-{max(ratio):.2f}")
    print("(means over cases; 'picked by': each case estimated with the factor where that reading is lowest)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_case_arguments(ap, scenario="paper,still")
    ap.add_argument("--factors", default="0.5,0.71,1,1.41,2",
                    help="the lens told, as multiples of the true focal length (default 0.5,0.71,1,1.41,2)")
    ap.add_argument("--search", default=None, metavar="GRID",
                    help="search the lens over these focal lengths (mm, comma-separated), as a product would")
    ap.add_argument("--reading", default="lifter", choices=READINGS, help="the reading the search minimises")
    ap.add_argument("--free-focal", action="store_true", help="add a row with the focal length free in the solve")
    args = ap.parse_args(argv)
    try:
        factors = [float(v) for v in args.factors.split(",") if v.strip()]
    except ValueError:
        ap.error(f"--factors must be numbers separated by commas, got {args.factors!r}")
    if not factors or min(factors) <= 0:
        ap.error("--factors must be positive numbers")
    grid = None
    if args.search is not None:
        try:
            grid = sorted(float(v) for v in args.search.split(",") if v.strip())
        except ValueError:
            ap.error(f"--search must be focal lengths in mm separated by commas, got {args.search!r}")
        if len(grid) < 3 or grid[0] <= 0:
            ap.error("--search needs three or more positive focal lengths")
    _, cases = chosen_cases(ap, args)
    t0 = time.time()
    results = []
    for c in cases:
        tracks, truth = film(c, args.max_s)
        true_mm = float(np.asarray(truth.focal_mm, dtype=float).ravel()[0])
        res = {"case": c, "assumed": solve(tracks, truth, None),
               "told": {k: solve(tracks, truth, k * true_mm) for k in factors}}
        if grid is not None:
            on_grid = [solve(tracks, truth, f) for f in grid]
            res["reading"] = args.reading
            res["searched"] = solve(tracks, truth, searched_focal(grid, [r[args.reading] for r in on_grid]))
        if args.free_focal:
            res["free"] = free_focal_solve(tracks, truth)
        results.append(res)
        print(f"{os.path.basename(c['clip'])} {c['scenario']} draw {c['draw']}: true lens {true_mm:.1f} mm", flush=True)
        print(_row("assumed", res["assumed"]))
        for k, r in res["told"].items():
            print(_row(f"{k:g}x", r))
        if "searched" in res:
            print(_row("searched", res["searched"]))
        if "free" in res:
            print(_row("free", res["free"]))
    summarize(results, factors)
    print(f"total {time.time() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
