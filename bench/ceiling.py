"""How close can the joint objective get? The evaluation's metrics of solves started at the synthetic truth.

    python bench/ceiling.py [BVH ...] [--builtin] [--max-frames 900] [--noise-px 1] [--iter 40] [--markdown]

Why: the joint method misses most of its accuracy targets (<= 0.2 / 0.5 pp proportions,
0.1 degrees of camera rotation, 15 / 40 mm per frame / whole clip, ...), and the gap has two possible
sources that call for different work.  *Search*: the start (paper camera, Taylor + DP depth signs)
lands in a wrong local minimum that a better start or a better move would leave.  *Model*: the
objective's own minimum near the truth is already off by that much at this noise, so no start can
do better without new information (a focal hint, a closer person, a better prior).  This script
splits them, clip by clip, with rows scored exactly as ``python -m core evaluate`` scores:

``truth``
    the true state itself, packed and unpacked as a solver state but not solved: every error should
    read about 0 (the check that the two truth starts below really start at the truth).
``joint``
    the shipped method (``estimate(tracks, "joint")``, no focal hint).
``truth-start``
    the objective of the shipped method's first solve: the same stance labels, camera prior, length
    prior and focal prior (the paper's run, no hint), but the LM solve started from the true poses,
    camera, focal lengths and bone lengths, ``--iter`` iterations (the camera free), then the shipped
    polish with the camera prior and the lengths held.  Where it ends at a lower cost than
    ``joint``, the gap between them is search error; where it ends higher, this objective does not
    prefer the truth (its inputs or priors pull away from it) and more search on it cannot help.  Since
    the shipped sign rounds hold the stance decided on the first solve
    (:data:`core.joint_solve.pipeline.STANCE_FROM_FIRST_SOLVE`), ``joint``'s final cost is on that
    stance's planted-foot labels and this row's on the paper's: compare the two costs with that in mind.
``oracle``
    an objective with every outside input right: the true stance (three states, flight included),
    no camera or length prior, the true frame-0 focal length as a user hint (a prior of the default
    sigma), started from the truth likewise.  Its errors are what the reprojection, bone-length,
    smoothness, joint-limit and planted-foot terms themselves allow at this noise.

``--rows`` also takes ``no-camera-prior`` and ``true-stance``: the truth start with the paper's camera
prior dropped, or with the true stance in place of the paper's, one input changed at a time.

The truth is used only to build the starts and the oracle's inputs; the solver and the scoring
are the product's own (``core.joint_solve``, ``core.evaluation.evaluate.score``).  The clips are filmed as
``evaluate`` films them (pan, tilt and zoom spells, seed 0), so the ``joint`` rows reproduce its
numbers.  Clips longer than the single-solve limit (1,200 frames) are refused: the truth starts
are single solves.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from core.camera import DEFAULT_FOCAL_MM, mm_per_pixel, pixels_to_film  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation.evaluate import BUILTIN_CLIPS, format_score, pooled, score, score_applies  # noqa: E402
from core.joint_solve import pipeline as pl  # noqa: E402
from core.joint_solve import solver as slv  # noqa: E402
from core.joint_solve.calibration import Calibration  # noqa: E402
from core.joint_solve.ground import planted_points  # noqa: E402
from core.joint_solve.stance import stance_codes  # noqa: E402
from core.skeleton import class_lengths_for_height  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402

ROWS = ("truth", "joint", "truth-start", "oracle")
#: Diagnostic rows, on request (``--rows``): the truth start with one input changed.
EXTRA_ROWS = ("no-camera-prior", "true-stance")


def truth_state(truth, stance) -> np.ndarray:
    """The packed solver state of the truth (poses in frame-0 camera axes, metres), with the true up
    direction (the world's vertical in frame-0 axes) and the planted ankles' median height along it."""
    up = np.asarray(truth.world_from_cam0, dtype=float)[2, :3]
    up = up / np.linalg.norm(up)
    planted = planted_points(truth.joints_3d, stance)
    offset = float(np.median(planted @ up)) if planted.size else 0.0
    return slv.pack(truth.joints_3d, np.radians(truth.rotvec_deg), np.log(truth.focal_mm),
                    np.asarray(truth.class_lengths_m, dtype=float), up, offset)


def truth_start(tracks, truth, iters: int, *, camera_prior: bool = True, true_stance: bool = False):
    """The shipped objective, solved from the truth: ``estimate_joint``'s own ``run_solve`` with the
    paper's stance, camera prior and lengths prior and the no-hint focal prior, only the start replaced.
    As in the shipped solve, the camera prior joins for the last
    :data:`~core.joint_solve.pipeline.CAMERA_PRIOR_POLISH_ITER` iterations, with the lengths held.

    ``camera_prior=False`` drops the paper's camera prior, ``true_stance=True`` puts the true stance in
    place of the paper's (the rows ``no-camera-prior`` and ``true-stance``): one input changed at a time,
    to see which one pulls the solve off the truth."""
    f0 = DEFAULT_FOCAL_MM
    paper = pl.paper_initialisation(tracks, None, truth.height_m)
    if paper is None:
        raise RuntimeError("the paper's method failed: the shipped objective cannot be rebuilt")
    props = paper["proportions"] if paper["proportions"] is not None else pl.DEFAULT_PROPORTIONS
    lengths = class_lengths_for_height(props, truth.height_m)
    stance = stance_codes(truth.stance) if true_stance else paper["stance"]
    cprior = pl._camera_prior(paper, f0) if camera_prior else None
    x, rep, prob = pl.run_solve(pixels_to_film(tracks.xy, tracks.image_size), None, stance, None, None,
                                tracks=tracks, height_m=truth.height_m,
                                focal_prior=(f0, pl.UNDETERMINED_FOCAL_SIGMA), max_iter=iters,
                                x0=truth_state(truth, stance),
                                camera_prior=pl._solve_camera_prior(cprior),
                                length_prior=pl._length_prior(paper, lengths))
    # as the shipped solve: the camera prior joins for the final iterations, lengths held
    x, rep, prob = pl._polish_with_camera_prior(prob, x, rep, cprior, pl._Ticker(None, None))
    calib = Calibration(focal_mm=f0, determined=False)
    return pl._to_estimate(tracks, prob, x, stance, truth.height_m, calib, [], rep, paper)


def oracle(tracks, truth, iters: int):
    """Every outside input right (see module docstring), solved from the truth (``iters`` 0: the truth row)."""
    stance = stance_codes(truth.stance)
    f0 = float(truth.focal_mm[0])
    prob = slv.Problem(film=pixels_to_film(tracks.xy, tracks.image_size), mm_per_px=mm_per_pixel(tracks.image_size),
                       fps=tracks.fps, height_m=truth.height_m, stance=stance, focal_prior_mm=f0)
    x = truth_state(truth, stance)
    if iters > 0:
        x, rep = slv.solve(prob, x, max_iter=iters)
    else:
        rep = slv.SolveReport(cost=float(slv.residuals(prob, x, with_jac=False)), iterations=0, converged=False)
    calib = Calibration(focal_mm=f0, determined=True)
    return pl._to_estimate(tracks, prob, x, stance, truth.height_m, calib, [], rep)


def _row(name: str, kind: str, sc: dict, cost: float, seconds: float) -> str:
    p = sc["proportions"]
    stance = sc["stance_accuracy"]
    return (f"{name[:40]:<40} {kind:<15} {p['mean_abs']:6.2f} {p['max_abs']:6.2f} "
            f"{format_score(sc['zoom_focal_error_pct']):>7} {sc['rotation_error_deg']:8.3f} "
            f"{sc['mpjpe_frame_mm']:7.1f} {sc['mpjpe_clip_mm']:7.1f} "
            f"{format_score(stance * 100 if score_applies(stance) else None, '.1f'):>7} "
            f"{cost:9.0f} {seconds:6.1f}")


def summary(rows: list[dict]) -> None:
    """Aggregates per row kind (:func:`core.evaluation.evaluate.pooled` over its clips), beside the targets."""
    print("\n== summary against the accuracy targets (<= 0.2 / 0.5 pp, 0.5 %, 0.1 deg, 15 / 40 mm, >= 97 %)")
    print(f"{'row':<15} {'mean pp':>7} {'max pp':>7} {'zoomf%':>7} {'rot deg':>8} {'mpjpe':>7} {'mpjpeC':>7} "
          f"{'stance%':>8}")
    for kind in ROWS + EXTRA_ROWS:
        scs = [r["score"] for r in rows if r["kind"] == kind]
        if not scs:
            continue
        a = pooled(scs)
        print(f"{kind:<15} {a['mean_pp']:7.3f} {a['max_pp']:7.2f} {a['zoom_focal_pct']:7.2f} {a['rotation_deg']:8.3f} "
              f"{a['mpjpe_frame_mm']:7.1f} {a['mpjpe_clip_mm']:7.1f} {a['stance_pct']:8.1f}")


def _cell(sc: dict) -> str:
    p = sc["proportions"]
    return (f"{p['mean_abs']:.2f} / {p['max_abs']:.2f}, {sc['rotation_error_deg']:.2f}, "
            f"{format_score(sc['zoom_focal_error_pct'])}, {sc['mpjpe_frame_mm']:.0f} / {sc['mpjpe_clip_mm']:.0f}")


def markdown(rows: list[dict], kinds: list[str]) -> None:
    """The per-clip table of the README: for each row kind proportions mean / max (pp), median rotation
    error (deg), zoom focal error (%), MPJPE per frame / whole clip (mm); and the final costs of the
    two rows that share the shipped objective."""
    both = "joint" in kinds and "truth-start" in kinds
    head = [f"{k}: pp mean / max, rotation deg, zoom %, MPJPE frame / clip mm" for k in kinds]
    if both:
        head.insert(kinds.index("truth-start") + 1, "cost, joint / truth-start")
    print("\n| clip | " + " | ".join(head) + " |")
    print("|---" * (len(head) + 1) + "|")
    for clip in dict.fromkeys(r["clip"] for r in rows):
        by = {r["kind"]: r for r in rows if r["clip"] == clip}
        cells = [_cell(by[k]["score"]) if k in by else "-" for k in kinds]
        if both:
            cells.insert(kinds.index("truth-start") + 1, f"{by['joint']['cost']:.0f} / {by['truth-start']['cost']:.0f}")
        print(f"| {os.path.splitext(clip)[0]} | " + " | ".join(cells) + " |")
    agg = []
    for k in kinds:
        a = pooled([r["score"] for r in rows if r["kind"] == k])
        agg.append(f"{a['mean_pp']:.3f} / {a['max_pp']:.2f}, {a['rotation_deg']:.2f}, {a['zoom_focal_pct']:.2f}, "
                   f"{a['mpjpe_frame_mm']:.0f} / {a['mpjpe_clip_mm']:.0f}")
    if both:
        agg.insert(kinds.index("truth-start") + 1, "")
    n = len(dict.fromkeys(r["clip"] for r in rows))
    print(f"| **{n} clips** (mean of means / max of maxima, medians of rotation and zoom, mean MPJPE) | "
          + " | ".join(agg) + " |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*", metavar="BVH")
    ap.add_argument("--builtin", action="store_true", help="also the built-in walk (the default with no BVH)")
    ap.add_argument("--max-frames", type=int, default=900)
    ap.add_argument("--noise-px", type=float, default=1.0)
    ap.add_argument("--iter", type=int, default=40, help="LM iterations of the truth-started solves")
    ap.add_argument("--rows", default=",".join(ROWS), help=f"comma list of {', '.join(ROWS + EXTRA_ROWS)}")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--markdown", action="store_true", help="also print the per-clip table as Markdown (README)")
    args = ap.parse_args(argv)
    kinds = [k for k in args.rows.split(",") if k]
    bad = [k for k in kinds if k not in ROWS + EXTRA_ROWS]
    if bad:
        ap.error(f"unknown row(s) {bad}; choose from {', '.join(ROWS + EXTRA_ROWS)}")
    clips = (list(BUILTIN_CLIPS) if args.builtin or not args.clips else []) + list(args.clips)
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores shared)")
    print(f"{'clip':<40} {'row':<15} {'meanpp':>6} {'maxpp':>6} {'zoomf%':>7} {'rot deg':>8} {'mpjpe':>7} "
          f"{'mpjpeC':>7} {'stance%':>7} {'cost':>9} {'sec':>6}")
    rows = []
    for clip in clips:
        motion = load_motion(clip, max_frames=args.max_frames, fps=30.0)
        tracks, truth = synthesize(motion, noise_px=args.noise_px, seed=args.seed)
        if truth.n_frames > pl.SINGLE_MAX:
            ap.error(f"{clip}: {truth.n_frames} frames; the truth starts are single solves (<= {pl.SINGLE_MAX})")
        name = os.path.basename(clip)
        for kind in kinds:
            t0 = time.perf_counter()
            if kind == "joint":
                est = estimate(tracks, "joint", height_m=truth.height_m)
            elif kind == "truth-start":
                est = truth_start(tracks, truth, args.iter)
            elif kind == "no-camera-prior":
                est = truth_start(tracks, truth, args.iter, camera_prior=False)
            elif kind == "true-stance":
                est = truth_start(tracks, truth, args.iter, true_stance=True)
            else:
                est = oracle(tracks, truth, 0 if kind == "truth" else args.iter)
            seconds = time.perf_counter() - t0
            sc = score(est, truth)
            cost = est.diagnostics["solver"]["cost"]
            rows.append({"clip": name, "kind": kind, "score": sc, "cost": cost})
            print(_row(name, kind, sc, cost, seconds), flush=True)
    summary(rows)
    if args.markdown:
        markdown(rows, [k for k in kinds if k != "truth"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
