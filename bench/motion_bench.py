"""3D motion benchmark: what an animator keys onto a rig, measured against the truth, case by case.

Every clip (BVH files on the command line, plus the built-in walk, run and standing figure) is filmed once per
scenario, with what users vary drawn per case (seeded by clip, scenario and draw): the lens
(18-85 mm, never told to the estimator), the frame rate (24, 30 or 60 fps) and the azimuth.
Scenarios, the ones the team tracks:

* ``paper``: the paper's tripod schedule (pan, tilt, zoom between still spells), 1 px noise;
* ``still``: a still camera, 0 px;
* ``detector``: a handheld operator (:mod:`core.synthetic.footage_sim.handheld`: pans at random, turning
  towards the person more often than away) and a real detector's errors
  (:data:`core.synthetic.footage_sim.detector.TYPICAL`), 1 px;
* ``background``: a handheld operator and 16 static background points tracked too (the camera from
  the scene, :mod:`core.scene_camera`), 1 px; here the whole-clip error is the one to watch.

The single-image posing (one frame, Taylor's method, true lengths, 0 px) is
``bench/single_image_bench.py --noise-px 0``, which uses the same mirrored-limb measure.

Per case: the share of frames with a mirrored limb (:func:`core.evaluation.metrics.mirrored_limb_pct`), the
share of the legs' and of the arms' bone-frames whose depth sign is wrong where the true bone is slanted
(:func:`core.evaluation.metrics.depth_sign_error_pct`: shallow flips a mirror count misses), the
per-frame P-MPJPE and the whole-clip error (one similarity), the planted ankles' speed while the
TRUE ankle is planted (the truth's contact), against the truth's own, the acceleration error after
one similarity for the clip (world jitter) and per frame (pose jitter), and the reprojection residual
(median over frames of the mean pixel distance of the observed joints to the projected estimate).

Clips are split into a tune and a report half by the SHA-1 of their file name, as in
``bench/robust_bench.py``; settings are chosen on ``tune``, numbers quoted from ``report``.  ``--half all``
takes every clip as one group, for a corpus kept for evaluation alone (nothing chosen on it), and
``--no-builtins`` leaves the built-in figures out.
``--cleanup both`` runs every case with and without the motion cleanup (:mod:`core.motion_cleanup`)
and prints both; ``--save DIR`` keeps each raw solve (cleanup off) with its truth, for tuning the
cleanup's settings offline (``--replay DIR``).  ``--true-focal`` tells the estimate frame 0's focal length,
as footage metadata would: what the unknown lens costs.  ``--phone assumed`` films every case with a phone
video's lens instead (:data:`PHONE_EQUIVALENT_MM`, 35 mm-equivalent) and gives the tracks what a phone's
file that states no lens gives them: the main camera assumed (:func:`core.lens.prior.phone_lens`);
``--phone none`` the same lenses with nothing told (the estimator's 50 mm default, a re-encoded file).
``--backwards`` plays every clip backwards in time: a person walking backwards, planted feet and all, whose
motion no training clip shows in that direction (the video lifter reads half a second of motion each way).
``--oracle-cue`` measures what a better lifter would give: the joint solve reads the truth's bone directions
in the lifter's place (``directions``), the lifter's own answer with its clear depth signs made right
(``signs``), or with the truth's slants on its own sides (``slants``).

    python bench/motion_bench.py /work/shared/data/bvh/*.bvh --scenario paper --half report
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.model_options import add_model_arguments, apply_model_arguments  # noqa: E402
from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.camera import project_to_pixels, rotation_matrix  # noqa: E402
from core.estimate import estimate  # noqa: E402
from core.evaluation import metrics  # noqa: E402
from core.lens.prior import focal_from_35mm_equivalent, phone_lens  # noqa: E402
from core.nanstats import nanmean  # noqa: E402
from core.skeleton import JOINTS  # noqa: E402
from core.synthetic.footage_sim import HandheldOperator  # noqa: E402
from core.synthetic.footage_sim.detector import TYPICAL  # noqa: E402
from core.synthetic.motion import Motion, load_motion  # noqa: E402
from core.synthetic.synth import synthesize  # noqa: E402
from core.synthetic.synth_camera import Spell  # noqa: E402

SCENARIOS: dict[str, dict] = {
    "paper": {"camera": "paper", "noise_px": 1.0, "detector": False, "static_points": 0},
    "still": {"camera": "still", "noise_px": 0.0, "detector": False, "static_points": 0},
    "detector": {"camera": "handheld", "noise_px": 1.0, "detector": True, "static_points": 0},
    "background": {"camera": "handheld", "noise_px": 1.0, "detector": False, "static_points": 16},
}
FRAME_RATES = (24.0, 30.0, 60.0)
#: ``--phone``: the 35 mm-equivalent focal lengths a phone's video is filmed with, drawn uniformly: the main
#: camera's 23-26 mm across its 4:3 sensor, cut to 16:9 (9 % longer) and by stabilisation (up to 10 % more);
#: the makers' figures (see :data:`core.lens.prior.PHONE_VIDEO_EQUIVALENT_MM`).
PHONE_EQUIVALENT_MM = (25.0, 31.0)
#: Every case's picture (pixels).
IMAGE_SIZE = (720, 480)
#: Added to the clips on the command line: the built-in walk and run, and the built-in standing figure (a
#: person who never steps, on the tune half by its name's SHA-1).
BUILTINS = ("builtin:walk", "builtin:run", "builtin:stand")
#: A clip estimated worse than this per frame (P-MPJPE, mm) should carry a warning.
WARN_MM = 150.0
#: A true ankle counts as planted on its contact frames where it is slower than this (m/s).
PLANTED_TRUE_MAX_M_S = 0.1


def draw_case(clip: str, scenario: str, k: int) -> dict:
    rng = _case_rng(clip, "motion-" + scenario, k)
    return {"clip": clip, "scenario": scenario, "draw": k, "seed": int(rng.integers(1 << 30)),
            "focal_mm": float(np.exp(rng.uniform(np.log(18.0), np.log(85.0)))),
            "fps": float(rng.choice(FRAME_RATES)), "view_offset_deg": float(rng.uniform(-90.0, 90.0)),
            **SCENARIOS[scenario]}


def phone_case(c: dict) -> dict:
    """The case filmed by a phone instead: its lens drawn from :data:`PHONE_EQUIVALENT_MM` (its own stream,
    so the rest of the case is as drawn)."""
    rng = np.random.default_rng([c["seed"], 35])
    return {**c, "focal_mm": focal_from_35mm_equivalent(float(rng.uniform(*PHONE_EQUIVALENT_MM)), IMAGE_SIZE)}


def backwards(motion: Motion) -> Motion:
    """``motion`` played backwards in time (contacts with it): a person walking backwards."""
    return dataclasses.replace(motion, name=motion.name + " backwards", joints=motion.joints[::-1].copy(),
                               contacts=motion.contacts[::-1].copy())


def film(c: dict, max_s: float):
    motion = load_motion(c["clip"], fps=c["fps"], max_frames=int(round(max_s * c["fps"])))
    if c.get("backwards"):
        motion = backwards(motion)
    kw = {}
    if c["camera"] == "handheld":
        kw["operator"] = HandheldOperator()
    elif c["camera"] == "still":
        kw["schedule"] = [Spell(0, motion.n_frames - 1, "still")]
    if c["detector"]:
        kw["detector"] = TYPICAL
    return synthesize(motion, focal_mm=c["focal_mm"], image_size=IMAGE_SIZE, noise_px=c["noise_px"], seed=c["seed"],
                      view_offset_deg=c["view_offset_deg"], static_points=c["static_points"], **kw)


def reprojection_px(joints: np.ndarray, rotvec_deg: np.ndarray, focal_mm: np.ndarray, tracks) -> float:
    """Median over frames of the mean distance (pixels) of the observed joints to the projected estimate."""
    cam = np.einsum("fij,fkj->fki", rotation_matrix(rotvec_deg), joints)
    uv = project_to_pixels(cam, np.asarray(focal_mm, dtype=float)[:, None], tracks.image_size)
    err = np.linalg.norm(uv - tracks.xy, axis=-1)
    per = np.array([np.nanmean(e) if np.isfinite(e).any() else np.nan for e in err])
    return float(np.nanmedian(per))


#: Which of :data:`core.evaluation.metrics.LIMB_BONES` are the arms' and which the legs'.
_ARM_BONES = [k for k, (_, c) in enumerate(metrics.LIMB_BONES)
              if JOINTS[c] in ("l_elbow", "l_wrist", "r_elbow", "r_wrist")]
_LEG_BONES = [k for k in range(len(metrics.LIMB_BONES)) if k not in _ARM_BONES]


def motion_scores(joints: np.ndarray, rotvec_deg, focal_mm, tracks, truth) -> dict:
    """Every 3D motion measure of one estimate (arrays in frame-0 camera axes) against ``truth``."""
    act = truth.joints_3d
    # the truth's contact, where its ankle really stands: the contacts of captured clips include the heel's
    # roll (their ankles move 100-150 mm/s on average there), which no lock should copy
    planted = metrics.planted_from_stance(truth.stance, truth.n_frames) & metrics.planted_from_speed(
        act, truth.fps, PLANTED_TRUE_MAX_M_S)
    feet = metrics.planted_foot_speed_mm_s(joints, act, truth.fps, planted)
    true_rotvec = getattr(truth, "rotvec_deg", None)       # a saved solve may hold none
    signs = (np.full(len(metrics.LIMB_BONES), np.nan) if true_rotvec is None
             else metrics.depth_sign_error_pct(joints, act, rotvec_deg, true_rotvec))
    return {"mirrored_pct": metrics.mirrored_limb_pct(joints, act),
            "sign_arms_pct": float(nanmean(signs[_ARM_BONES])), "sign_legs_pct": float(nanmean(signs[_LEG_BONES])),
            "mpjpe_frame_mm": metrics.mpjpe_per_frame_m(joints, act) * 1000.0,
            "mpjpe_clip_mm": metrics.mpjpe_clip_m(joints, act) * 1000.0,
            "planted_mm_s": feet["estimated_mm_s"], "planted_true_mm_s": feet["true_mm_s"],
            "planted_excess_mm_s": feet["excess_mm_s"], "planted_median_mm_s": feet["estimated_median_mm_s"],
            "accel_world_mm_s2": metrics.acceleration_error_mm_s2(joints, act, truth.fps, "clip"),
            "accel_world_rigid_mm_s2": metrics.acceleration_error_mm_s2(joints, act, truth.fps, "clip-rigid"),
            "accel_pose_mm_s2": metrics.acceleration_error_mm_s2(joints, act, truth.fps, "frame"),
            "reproj_px": reprojection_px(joints, rotvec_deg, focal_mm, tracks)}


def _arrays(est):
    return (np.array([f.joints_3d for f in est.frames], dtype=float),
            np.array([f.rotvec_deg for f in est.frames], dtype=float),
            np.array([f.focal_mm for f in est.frames], dtype=float))


#: What ``--oracle-cue`` gives the joint solve in place of the video lifter's reading, and the case's true bone
#: directions it reads them from (each frame's camera axes, the clip's own frames).
ORACLE_CUES = ("directions", "signs", "slants")
_oracle: dict = {"kind": None, "dirs": None}


def camera_bone_directions(joints: np.ndarray, rotvec_deg: np.ndarray) -> np.ndarray:
    """(F, 16, 3) unit bone vectors of ``joints`` (F, 17, 3, frame-0 camera axes) in each frame's camera axes."""
    from core.motion_prior.features import bone_vectors

    cam = np.einsum("fij,fkj->fki", rotation_matrix(np.asarray(rotvec_deg, dtype=float)), joints)
    bones = bone_vectors(cam)
    return bones / np.linalg.norm(bones, axis=-1, keepdims=True)


def true_bone_directions(truth) -> np.ndarray:
    """(F, 16, 3) the truth's unit bone vectors in each frame's camera axes."""
    return camera_bone_directions(truth.joints_3d, truth.rotvec_deg)


def use_oracle_cue(kind: str) -> None:
    """From now on the joint solve's lifter cue (:func:`core.joint_solve.pipeline.lifter_cue`, the sign choice's
    and the solve's) is an oracle: ``"directions"`` the truth's bone directions (a lifter that is always
    right), ``"signs"`` the lifter's own answer with its depth sign turned to the truth's wherever the true bone
    leans out of the picture's plane by more than :data:`core.evaluation.metrics.MIN_SLANT` (a lifter right
    about every clear side, its slants as they are), ``"slants"`` the lifter's answer with the truth's slant
    out of the picture (depth over length) on the lifter's own side, its direction in the picture kept (a
    lifter right about how far each bone leans, not which way).  :func:`run_case` gives it each case's
    truth."""
    from core.joint_solve import pipeline

    shipped = pipeline.lifter_cue

    def oracle(rays, fps=None):
        n = rays.shape[0]
        dirs = _oracle["dirs"]
        step = max(1, int(round(dirs.shape[0] / n)))            # the estimate's working rate: every k-th frame
        dirs = dirs[::step][:n]
        if dirs.shape[0] != n:
            raise RuntimeError(f"the oracle has {dirs.shape[0]} frames for {n}")
        if kind == "directions":
            return dirs.copy()
        own = shipped(rays, fps).copy()
        if kind == "slants":
            z = np.where(own[..., 2] < 0, -1.0, 1.0) * np.abs(dirs[..., 2])
            across = own[..., :2] / np.maximum(np.linalg.norm(own[..., :2], axis=-1, keepdims=True), 1e-12)
            return np.concatenate([across * np.sqrt(np.maximum(1.0 - z * z, 0.0))[..., None], z[..., None]], axis=-1)
        flip = (np.sign(own[..., 2]) != np.sign(dirs[..., 2])) & (np.abs(dirs[..., 2]) > metrics.MIN_SLANT)
        own[..., 2] = np.where(flip, -own[..., 2], own[..., 2])
        return own

    _oracle["kind"] = kind
    pipeline.lifter_cue = oracle


def run_case(c: dict, max_s: float, cleanups: list[str], save: str | None = None, true_focal: bool = False,
             phone: str | None = None) -> list[dict]:
    if phone is not None:
        c = {**phone_case(c), "phone": phone}
    tracks, truth = film(c, max_s)
    if _oracle["kind"] is not None:
        _oracle["dirs"] = true_bone_directions(truth)
    if phone == "assumed":
        tracks = tracks.replaced(meta={**tracks.meta, **phone_lens("the bench's phone", tracks.image_size).meta()})
    rows = []
    for mode in cleanups:
        kw = {} if mode == "on" else {"motion_cleanup": None}
        if true_focal:
            kw["focal_mm"] = float(np.asarray(truth.focal_mm, dtype=float).ravel()[0])
        t0 = time.perf_counter()
        est = estimate(tracks, "joint", **kw)
        sec = time.perf_counter() - t0
        j, rv, fm = _arrays(est)
        rows.append({**c, "cleanup": mode, "frames": tracks.n_frames, "seconds": sec,
                     "trusted": bool(est.diagnostics.get("trusted")),
                     "warnings": list(est.diagnostics.get("warnings", [])),
                     **motion_scores(j, rv, fm, tracks, truth)})
        if save and mode == "off":
            os.makedirs(save, exist_ok=True)
            name = f"{os.path.basename(c['clip'])}-{c['scenario']}-{c['draw']}.npz"
            np.savez_compressed(os.path.join(save, name), joints=j, rotvec_deg=rv, focal_mm=fm, xy=tracks.xy,
                                image_size=np.array(tracks.image_size), fps=tracks.fps,
                                world_from_cam0=np.array(est.diagnostics["world_from_cam0"]),
                                truth_joints=truth.joints_3d, truth_rotvec_deg=np.asarray(truth.rotvec_deg),
                                truth_stance=np.array(
                                    [{"l": 0, "r": 1}.get(s, -1) for s in truth.stance]),
                                stance=np.array([{"l": 0, "r": 1}.get(f.stance, -1) for f in est.frames]),
                                height_m=est.height_m, case=json.dumps(c))
    return rows


def cases(clips: list[str], scenarios: list[str], half: str, draws: int, first: int | None) -> list[dict]:
    """The deterministic case list: clips of the asked half, every scenario, ``draws`` draws each; ``first``
    keeps the first n cases of each scenario."""
    out = []
    for s in scenarios:
        cs = [draw_case(clip, s, k) for clip in clips if half in ("both", "all") or half_of(clip) == half
              for k in range(draws)]
        out += cs[:first] if first else cs
    return out


KEYS = (("mirrored_pct", "mirror %", ".1f"), ("sign_legs_pct", "sign legs %", ".1f"),
        ("sign_arms_pct", "sign arms %", ".1f"), ("mpjpe_frame_mm", "P-MPJPE", ".0f"),
        ("mpjpe_clip_mm", "clip mm", ".0f"),
        ("planted_mm_s", "plant mm/s", ".0f"), ("planted_true_mm_s", "true mm/s", ".0f"),
        ("planted_excess_mm_s", "excess", ".0f"), ("accel_world_mm_s2", "acc world", ".0f"),
        ("accel_pose_mm_s2", "acc pose", ".0f"), ("reproj_px", "reproj px", ".2f"), ("seconds", "sec", ".1f"))


def _fmt(v, spec):
    return format(v, spec) if v is not None and np.isfinite(v) else "-"


def print_row(r: dict, out=None) -> None:
    out = out or sys.stdout
    print(f"{os.path.basename(r['clip'])[:34]:<34} {r['scenario']:<10} {r['cleanup']:<3} {r['fps']:3.0f} fps "
          f"{r['focal_mm']:3.0f} mm | " + " ".join(f"{h} {_fmt(r[k], s)}" for k, h, s in KEYS), file=out, flush=True)


def summarize(rows: list[dict], out=None) -> None:
    out = out or sys.stdout
    print("\n| scenario | half | cleanup | cases | " + " | ".join(h for _, h, _ in KEYS) + " |", file=out)
    print("|---" * (4 + len(KEYS)) + "|", file=out)
    groups = []
    for s in SCENARIOS:
        for h in ("tune", "report", "all"):
            for mode in ("off", "on"):
                rs = [r for r in rows if (r["scenario"], r["half"], r["cleanup"]) == (s, h, mode)]
                if not rs:
                    continue
                groups.append((f"{s} / {h} / {mode}", rs))
                med = [_fmt(float(np.nanmedian([r[k] for r in rs])), spec) for k, _, spec in KEYS]
                print(f"| {s} | {h} | {mode} | {len(rs)} | " + " | ".join(med) + " |", file=out)
    print("(median over cases; mirror %: frames with a limb > 45 deg off; sign legs / arms %: limb bone-frames "
          "slanted > 0.15 in depth with the wrong depth sign; P-MPJPE: per-frame similarity, mm; clip mm: "
          "one similarity for the clip; plant mm/s: estimated ankle speed while the true ankle is planted, true mm/s "
          "the truth's, excess their difference; acc: acceleration error mm/s^2, world = clip alignment, pose = "
          "per frame; reproj px: median frame's mean residual)", file=out)
    for name, rs in groups:
        excess = np.array([r["planted_excess_mm_s"] for r in rs], dtype=float)
        print(f"{name}: means over cases: mirrored frames {np.mean([r['mirrored_pct'] for r in rs]):.1f} %, "
              f"P-MPJPE {np.mean([r['mpjpe_frame_mm'] for r in rs]):.1f} mm, whole clip "
              f"{np.mean([r['mpjpe_clip_mm'] for r in rs]):.0f} mm; planted ankles within 30 mm/s of the truth's in "
              f"{int(np.sum(np.abs(excess) <= 30.0))}/{len(rs)} cases", file=out)
    for mode in dict.fromkeys(r["cleanup"] for r in rows):
        worst = [r for r in rows if r["cleanup"] == mode and r["mpjpe_frame_mm"] > WARN_MM]
        print(f"cleanup {mode}: cases over {WARN_MM:.0f} mm per frame: {len(worst)}, of them without a warning: "
              f"{sum(not r['warnings'] for r in worst)}, marked trusted: {sum(r['trusted'] for r in worst)}", file=out)


def add_case_arguments(ap, scenario: str = "paper") -> None:
    """The options that choose the cases (clips, scenarios, half, draws, length), shared by the benches that
    measure on this bench's cases."""
    ap.add_argument("clips", nargs="*", help="BVH files (the built-in walk, run and standing figure are always added)")
    ap.add_argument("--scenario", default=scenario,
                    help=f"comma-separated scenarios of {', '.join(SCENARIOS)}, or 'all' (default {scenario})")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both", "all"],
                    help="the clips' half (tune, report), both halves apart, or all clips as one group: a corpus kept "
                         "for evaluation alone (default report)")
    ap.add_argument("--no-builtins", action="store_true", help="only the clips given, not the built-in figures")
    ap.add_argument("--draws", type=int, default=1, help="draws per clip and scenario (default 1)")
    ap.add_argument("--first", type=int, default=None, help="only the first n cases of each scenario")
    ap.add_argument("--max-s", type=float, default=8.0, help="seconds of each clip (default 8)")


def chosen_cases(ap, args) -> tuple[list[str], list[dict]]:
    """(the scenarios, the cases) the options of :func:`add_case_arguments` choose."""
    scen = list(SCENARIOS) if args.scenario == "all" else [s.strip() for s in args.scenario.split(",") if s.strip()]
    bad = [s for s in scen if s not in SCENARIOS]
    if bad:
        ap.error(f"unknown scenario(s) {bad}; choose from {list(SCENARIOS)}")
    clips = list(args.clips) + ([] if args.no_builtins else [c for c in BUILTINS if c not in args.clips])
    return scen, cases(clips, scen, args.half, args.draws, args.first)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_case_arguments(ap)
    ap.add_argument("--cleanup", default="on", choices=["on", "off", "both"],
                    help="the motion cleanup on (default, as shipped), off, or both side by side")
    ap.add_argument("--save", default=None, metavar="DIR", help="keep each raw solve (cleanup off) as .npz here")
    ap.add_argument("--json", default=None)
    ap.add_argument("--true-focal", action="store_true",
                    help="tell the estimate the lens (frame 0's true focal length), as footage metadata would")
    ap.add_argument("--phone", choices=["assumed", "none"], default=None,
                    help="film with a phone video's lens; 'assumed': the tracks carry the phone's assumed main "
                         "camera, as a phone's file that states no lens gives; 'none': nothing told (50 mm)")
    ap.add_argument("--backwards", action="store_true",
                    help="play every clip backwards in time (a person walking backwards)")
    ap.add_argument("--oracle-cue", choices=ORACLE_CUES, default=None,
                    help="what a better lifter would give: the truth's bone directions in the lifter's place "
                         "('directions'), the lifter's own with every clear depth sign made right ('signs'), or "
                         "with the truth's slants on its own sides ('slants')")
    add_model_arguments(ap, joint_solve=True)
    args = ap.parse_args(argv)
    apply_model_arguments(args)
    if args.oracle_cue:
        use_oracle_cue(args.oracle_cue)
    _, chosen = chosen_cases(ap, args)
    modes = ["off", "on"] if args.cleanup == "both" else [args.cleanup]
    if args.save and "off" not in modes:
        modes = ["off"] + modes
    rows = []
    t0 = time.time()
    for c in chosen:
        if args.backwards:
            c = {**c, "backwards": True}
        for r in run_case(c, args.max_s, modes, args.save, args.true_focal, args.phone):
            r["half"] = "all" if args.half == "all" else half_of(c["clip"])
            rows.append(r)
            print_row(r)
    summarize(rows)
    print(f"total {time.time() - t0:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
