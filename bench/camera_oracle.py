"""Where the camera from the person alone goes wrong: the joint method given parts of the truth.

On the unseen-footage benchmark's ``target`` cases (handheld operator, unknown lens, a detector's errors,
:mod:`robust_bench`) the camera from the person alone is degrees off.  This runs each case several times,
handing the joint method one more piece of the truth each time, and reports the camera's median rotation
error per case:

* ``shipped``: as a user runs it;
* ``lens``: the true focal length given (as ``--focal-mm``);
* ``lens+stance``: also the true planted foot per frame (neither in a flight phase) in place of the
  paper's stance, held through the solve;
* ``lens+stance+start``: also the true camera as the solve's start, with no camera prior: whether the
  objective's minimum lies near the truth;
* ``drifted start``: the same, started from the true camera turned by a slow pan drift (0 at frame 0 to
  :data:`DRIFT_DEG` at the end): whether the solve comes back.  ``cost ratio`` is the drifted solve's final
  cost over the true-start solve's, both on the true-start run's problem: near 1 means the person alone
  cannot tell the drift from the truth;
* ``footprints``: no joint solve: the pan and tilt by least squares over the whole clip from the true
  planted feet and the true focal length (each contact one static direction, the camera's angular
  acceleration as a prior): how far the footprints alone pin the camera.

The stance and camera oracles replace internals of :mod:`core.joint_solve.pipeline` for the run (a
diagnostic, not an API).  Tune half by default: it is for choosing what to build.

    python bench/camera_oracle.py ../shared/data/bvh/*.bvh [--half tune] [--draws 3]
"""

from __future__ import annotations

import argparse
import os
import sys
from multiprocessing import Pool

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from robust_bench import draw_case, film_case, half_of  # noqa: E402
from scipy.sparse.linalg import spsolve  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

import core.joint_solve.pipeline as pipeline  # noqa: E402
import core.joint_solve.solver as slv  # noqa: E402
from core.camera import pan_tilt_roll_matrix, pixels_to_film, rotvec_deg  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation import metrics  # noqa: E402
from core.joint_solve.stance import stance_codes  # noqa: E402
from core.peng_li.virtual_scale import stance_runs  # noqa: E402
from core.skeleton import FEET  # noqa: E402
from core.track_cleaning import clean_tracks  # noqa: E402
from core.track_cleaning.residual import DEFAULT_RESIDUAL  # noqa: E402

MODES = ("shipped", "lens", "lens+stance", "lens+stance+start", "drifted start", "footprints")
COLUMNS = MODES + ("cost ratio",)
#: The drifted start's pan at the clip's end, degrees (its median error over the clip is half of it).
DRIFT_DEG = 2.0


def footprint_rotvec_deg(feet_film, stance, focal_mm, fps, accel_deg_s2=20.0, foot_rad=0.002):
    """(F, 3) camera rotation vectors (degrees) holding every contact's foot still (see the docstring)."""
    n = feet_film.shape[0]
    f = np.broadcast_to(np.asarray(focal_mm, dtype=float), (n,))[:, None]
    x, y = feet_film[..., 0], feet_film[..., 1]
    ang = np.stack([np.arctan2(x, f), np.arctan2(y, np.hypot(x, f))], axis=-1)     # (F, 2 feet, 2)
    runs = stance_runs(np.asarray(stance), 2)              # contacts of two frames or more
    obs = np.array([(fr, k, foot) for k, (foot, a, b) in enumerate(runs) for fr in range(a, b)])
    nk, m = len(runs), len(obs)
    a_obs = sp.csr_matrix((np.r_[np.ones(m), -np.ones(m)], (np.r_[np.arange(m), np.arange(m)],
                                                           np.r_[obs[:, 0], n + obs[:, 1]])), shape=(m, n + nk))
    sig_a = np.radians(accel_deg_s2) / fps ** 2
    i0 = np.arange(n - 2)
    a_acc = sp.csr_matrix((np.r_[np.ones(n - 2), -2 * np.ones(n - 2), np.ones(n - 2)] / sig_a,
                           (np.tile(i0, 3), np.r_[i0, i0 + 1, i0 + 2])), shape=(n - 2, n + nk))
    fixed = (a_acc.T @ a_acc).tocsc() + sp.csc_matrix(([1e12], ([0], [0])), shape=(n + nk, n + nk))
    pt = np.zeros((n, 2))
    for axis in range(2):
        u = ang[obs[:, 0], obs[:, 2], axis]
        ok = np.isfinite(u)
        w, u = ok / foot_rad ** 2, np.where(ok, u, 0.0)
        lhs = (a_obs.T @ sp.diags(w) @ a_obs + fixed).tocsc() + sp.identity(n + nk, format="csc") * 1e-9
        pt[:, axis] = spsolve(lhs, -(a_obs.T @ (w * u)))[:n]
    return rotvec_deg(pan_tilt_roll_matrix(np.degrees(pt[:, 0]), np.degrees(pt[:, 1])))


def run_case(arg):
    clip, draw, max_s = arg
    c = draw_case(clip, "target", draw)
    tracks, truth = film_case(c, max_s)
    true_stance = stance_codes(truth.stance)
    original = (pipeline.paper_initialisation, pipeline.STANCE_FROM_FIRST_SOLVE, pipeline._camera_prior,
                pipeline._to_estimate)
    drift = Rotation.from_euler("y", np.linspace(0.0, DRIFT_DEG, tracks.n_frames)[:, None], degrees=True)
    starts = {"lens+stance+start": np.radians(truth.rotvec_deg),
              "drifted start": (drift * Rotation.from_rotvec(np.radians(truth.rotvec_deg))).as_rotvec()}
    solved = {}
    out = {"clip": os.path.basename(clip), "draw": draw}
    for mode in MODES:
        if mode == "footprints":
            clean, _ = clean_tracks(tracks)
            film = pixels_to_film(clean.xy, clean.image_size)
            feet = np.stack([film[:, FEET["l"]], film[:, FEET["r"]]], axis=1)
            est_rv = footprint_rotvec_deg(feet, true_stance, truth.focal_mm, tracks.fps)
            out[mode] = metrics.rotation_error_deg(est_rv, truth.rotvec_deg)
            continue

        def with_truth(tr, focal_mm, height_m, scene=None, mode=mode):
            p = original[0](tr, focal_mm, height_m, scene)
            if p is not None and len(p["stance"]) == len(true_stance):
                p["stance"] = true_stance.copy()
                if mode in starts:
                    p["rotvec"] = starts[mode]
                    p["focal_ratio"] = truth.focal_mm / truth.focal_mm[0]
                    p["focal0"] = float(truth.focal_mm[0])
            return p

        try:
            if "stance" in mode or mode in starts:
                pipeline.paper_initialisation = with_truth
                pipeline.STANCE_FROM_FIRST_SOLVE = False
            if mode in starts:
                pipeline._camera_prior = lambda *a, **k: None

                def keep(tr, prob, x, *a, mode=mode, **k):
                    solved[mode] = (prob, x)
                    return original[3](tr, prob, x, *a, **k)

                pipeline._to_estimate = keep
            # one pass (no residual re-solve), so both start modes solve the same problem
            est = estimate(tracks, "joint", focal_mm=None if mode == "shipped" else c["focal_mm"],
                           residual=None if mode in starts else DEFAULT_RESIDUAL)
        finally:
            (pipeline.paper_initialisation, pipeline.STANCE_FROM_FIRST_SOLVE, pipeline._camera_prior,
             pipeline._to_estimate) = original
        out[mode] = metrics.rotation_error_deg(np.array([f.rotvec_deg for f in est.frames]), truth.rotvec_deg)
    prob, x_true = solved["lens+stance+start"]
    out["cost ratio"] = (float(slv.residuals(prob, solved["drifted start"][1], with_jac=False))
                         / float(slv.residuals(prob, x_true, with_jac=False)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="tune", choices=["tune", "report", "both"])
    ap.add_argument("--draws", type=int, default=3)
    ap.add_argument("--max-s", type=float, default=30.0)
    args = ap.parse_args(argv)
    clips = [c for c in list(args.clips) + ["builtin:walk", "builtin:run"]
             if args.half == "both" or half_of(c) == args.half]
    with Pool(2) as pool:
        rows = pool.map(run_case, [(c, d, args.max_s) for c in clips for d in range(args.draws)])
    print("| clip | draw | " + " | ".join(COLUMNS) + " |")
    print("|---|---|" + "---|" * len(COLUMNS))
    for r in rows:
        print(f"| {r['clip']} | {r['draw']} | " + " | ".join(f"{r[m]:.2f}" for m in COLUMNS) + " |")
    print("| median | | " + " | ".join(f"{np.median([r[m] for r in rows]):.2f}" for m in COLUMNS) + " |")
    print("| p95 | | " + " | ".join(f"{np.quantile([r[m] for r in rows], 0.95):.2f}" for m in COLUMNS) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
