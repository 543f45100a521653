"""Two uses of the shipped pose prior (:func:`core.motion_prior.load_default`), measured on its current file.

Why: ``docs/motion_prior.md`` quotes what the prior does for the multi-camera fill-in and for the
self-check; the prior file is retrained from time to time, so those numbers must be measurable again
by a command line rather than by hand.

* ``multiview`` (one-view fill-in, :mod:`core.multiview.one_view`): as
  ``tests/core/test_multiview.py::test_joints_one_view_sees_are_placed_on_its_ray_by_the_pose_prior``,
  the built-in walk and run (150 frames) filmed by ring cameras (``ring_cameras(motion, views, seed=1)``,
  1 px, ``film_views(..., seed=1)``), the given cameras; a knee, an ankle, an elbow and a wrist
  (l_knee, l_ankle, r_elbow, r_wrist) hidden from every view but the first for frames 30-119.  The
  hidden joints' mean error (mm, first camera's axes) when they are filled in time
  (``pipeline.USE_ONE_VIEW`` off), placed on the first view's ray at the point nearer that time fill
  (the prior disabled, as the test does it), and on the ray at the point the prior picks (the default).
* ``selfcheck`` (:func:`core.self_check.checks._mirrored_limb_frames`, ``SelfCheckSettings.mirrored_gain``):
  how often the per-frame rule marks TRUE motions, and how often it marks them with one limb bone
  mirrored in depth.  Each clip (the BVH files given, plus the built-in walk and run; tune / report
  halves as in ``bench/robust_bench.py``), its first ``--frames`` frames at 30 fps, is seen from one
  random side per draw (heading anywhere, elevation within +-20 degrees, ``_case_rng(clip,
  "selfcheck", draw)``), its joints in camera axes (x right, y down, z forward: the check's depth is
  z).  "mirrored": per frame one limb bone, drawn among those whose depth over length exceeds 0.3, has
  its vector's depth negated (the bones below it carried along).  Frames pooled over the half's clips.
  Then the built-in walk's joint estimate (still camera, 1 px, 50 mm) clean and with both shanks
  mirrored in depth, the share of frames marked counted as
  ``tests/core/test_self_check.py::test_frames_with_a_limb_mirrored_in_depth_are_marked_and_flagged``
  counts it (``len(implausible_frames) / len(frames)``; the test's bound: above a quarter).

    python bench/prior_uses_bench.py ../shared/data/bvh/*.bvh [--part multiview|selfcheck|all] [--frames 300]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

import core.motion_prior as motion_prior  # noqa: E402
from bench.prior_bench import random_views  # noqa: E402
from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.motion_prior.evaluation import LIMB_BONES  # noqa: E402
from core.motion_prior.features import bone_vectors, joints_from_bones  # noqa: E402
from core.self_check.checks import SelfCheckSettings, _mirrored_limb_frames  # noqa: E402
from core.skeleton import JOINT_INDEX  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402

HIDDEN = ("l_knee", "l_ankle", "r_elbow", "r_wrist")
HIDDEN_FRAMES = slice(30, 120)
#: Depth over length above which a limb bone may be mirrored for the "mirrored" share.
OUT_OF_PLANE = 0.3


# ---------------------------------------------------------------- multiview: one-view fill-in

def multiview_case(clip: str, n_views: int, frames: int) -> dict:
    """The hidden joints' mean error (mm) per fill: time, nearer (prior off), prior."""
    from core.multiview import estimate_multiview
    from core.multiview import pipeline as mv
    from core.multiview.synth import film_views, ring_cameras

    motion = load_motion(clip, max_frames=frames)
    cams = ring_cameras(motion, n_views, seed=1)
    views = film_views(motion, cams, noise_px=1.0, seed=1)
    hidden = [JOINT_INDEX[n] for n in HIDDEN]
    for v in views[1:]:
        v.xy[HIDDEN_FRAMES, hidden] = np.nan
    truth = cams[0].to_camera(motion.joints)[HIDDEN_FRAMES][:, hidden]

    def hidden_error() -> float:
        est = estimate_multiview(views, cameras=cams)
        joints = np.array([f.joints_3d for f in est.frames])[HIDDEN_FRAMES][:, hidden]
        return 1000 * float(np.mean(np.linalg.norm(joints - truth, axis=-1)))

    use_one_view, load_default = mv.USE_ONE_VIEW, motion_prior.load_default
    out = {}
    try:
        out["prior"] = hidden_error()
        mv.USE_ONE_VIEW = False
        out["time"] = hidden_error()
        mv.USE_ONE_VIEW = True
        motion_prior.load_default = lambda: None
        out["nearer"] = hidden_error()
    finally:
        mv.USE_ONE_VIEW, motion_prior.load_default = use_one_view, load_default
    return out


def run_multiview(frames: int) -> None:
    rows = []
    for clip in ("builtin:walk", "builtin:run"):
        for n_views in (2, 3):
            t0 = time.process_time()
            r = multiview_case(clip, n_views, frames)
            rows.append((clip, n_views, r))
            print(f"multiview {clip} {n_views} views: time {r['time']:.0f} mm, nearer {r['nearer']:.0f} mm, "
                  f"prior {r['prior']:.0f} mm ({time.process_time() - t0:.1f} s CPU)", flush=True)
    print(f"\nOne-view fill-in: {', '.join(HIDDEN)} hidden from every view but the first for frames "
          f"{HIDDEN_FRAMES.start}-{HIDDEN_FRAMES.stop - 1} ({HIDDEN_FRAMES.stop - HIDDEN_FRAMES.start} frames); "
          "the hidden joints' mean error\n")
    print("| clip | views | time fill | on the ray nearer the time fill | on the ray by the prior |")
    print("|---|---|---|---|---|")
    for clip, n_views, r in rows:
        print(f"| {clip.split(':')[-1]} | {n_views} | {r['time']:.0f} mm | {r['nearer']:.0f} mm "
              f"| {r['prior']:.0f} mm |")


# ---------------------------------------------------------------- selfcheck: frames marked

def mirror_one_limb(cam: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(joints with one limb bone per frame mirrored in depth (F, 17, 3), frames where one could be (F,) bool):
    the bone drawn among the limb bones whose depth over length exceeds :data:`OUT_OF_PLANE`."""
    bones = bone_vectors(cam)
    limbs = np.array(LIMB_BONES)
    b = bones[:, limbs]
    with np.errstate(all="ignore"):
        out = np.abs(b[..., 2]) / np.linalg.norm(b, axis=-1) > OUT_OF_PLANE
    can = out.any(axis=1)
    for f in np.flatnonzero(can):
        k = limbs[rng.choice(np.flatnonzero(out[f]))]
        bones[f, k, 2] *= -1.0
    return joints_from_bones(bones, cam[:, 0]), can


def marked(cam: np.ndarray, gain: float) -> np.ndarray:
    """(F,) bool: the frames the self-check's pose rule marks at ``gain`` nats."""
    frames, _ = _mirrored_limb_frames(cam, SelfCheckSettings(mirrored_gain=gain))
    out = np.zeros(len(cam), dtype=bool)
    out[frames] = True
    return out


def selfcheck_clip(clip: str, frames: int, draws: int, gains: list[float]) -> dict:
    motion = load_motion(clip, fps=30.0, max_frames=frames)
    out = {"true": {g: [] for g in gains}, "mirrored": {g: [] for g in gains}}
    for draw in range(draws):
        rng = _case_rng(clip, "selfcheck", draw)
        R = random_views(1, rng)[0]                     # world (Y up) -> camera (x right, y down, z forward)
        cam = motion.joints @ R.T
        bad, can = mirror_one_limb(cam, rng)
        for g in gains:
            out["true"][g].append(marked(cam, g))
            out["mirrored"][g].append(marked(bad, g)[can])
    return {k: {g: np.concatenate(v) for g, v in d.items()} for k, d in out.items()}


def walk_estimate_check(gains: list[float]) -> dict:
    """The built-in walk's estimate, clean and with both shanks mirrored in depth (as the self-check's test)."""
    from core.estimate import estimate
    from core.motion_prior.evaluation import with_bones_mirrored
    from core.self_check import check_estimate
    from core.self_check.reprojection import camera_points
    from core.synthetic.synth import synthesize

    tracks, _ = synthesize(load_motion("builtin:walk", fps=30.0), kinds="still", noise_px=1.0, seed=0)
    est = estimate(tracks, "joint", focal_mm=50.0)
    bad = with_bones_mirrored(est, [JOINT_INDEX[n] - 1 for n in ("l_ankle", "r_ankle")])
    out = {"frames": len(est.frames)}
    for name, e in (("clean", est), ("shanks mirrored", bad)):
        check = check_estimate(e, tracks)
        out[name] = {"default": len(check["implausible_frames"]) / len(e.frames),
                     "pose flags": [f["code"] for f in check["flags"]].count("pose")}
        cam = camera_points(e)[0]
        for g in gains:
            out[name][g] = float(np.mean(marked(cam, g)))
    return out


def run_selfcheck(clips: list[str], frames: int, draws: int, gains: list[float], walk: bool) -> None:
    pooled: dict = {}
    for clip in list(clips) + ["builtin:walk", "builtin:run"]:
        half = half_of(clip)
        r = selfcheck_clip(clip, frames, draws, gains)
        acc = pooled.setdefault(half, {"clips": 0, "true": {g: [] for g in gains}, "mirrored": {g: [] for g in gains}})
        acc["clips"] += 1
        for k in ("true", "mirrored"):
            for g in gains:
                acc[k][g].append(r[k][g])
        parts = ", ".join(f"{g:g} nats {100 * r['true'][g].mean():.1f} / {100 * r['mirrored'][g].mean():.1f} %"
                          for g in gains)
        print(f"selfcheck {half} {os.path.basename(clip)} ({len(r['true'][gains[0]])} frames): "
              f"marked true / one limb mirrored: {parts}", flush=True)
    print(f"\nSelf-check on true motions (first {frames} frames at 30 fps, {draws} random side(s) per clip; "
          f"mirrored: one limb bone with depth/length > {OUT_OF_PLANE} per frame)\n")
    print("| half | clips | frames | threshold | frames marked | frames marked, one limb bone mirrored |")
    print("|---|---|---|---|---|---|")
    for half in ("tune", "report"):
        if half not in pooled:
            continue
        acc = pooled[half]
        for g in gains:
            t, m = np.concatenate(acc["true"][g]), np.concatenate(acc["mirrored"][g])
            print(f"| {half} | {acc['clips']} | {len(t)} | {g:g} nats | {100 * t.mean():.1f} % | "
                  f"{100 * m.mean():.1f} % ({len(m)} frames) |")
    if not walk:
        return
    t0 = time.process_time()
    w = walk_estimate_check(gains)
    print(f"\nThe built-in walk's joint estimate (still camera, 1 px, 50 mm, {w['frames']} frames; "
          f"{time.process_time() - t0:.1f} s CPU): frames marked\n")
    default = SelfCheckSettings().mirrored_gain
    print(f"| estimate | check_estimate ({default:g} nats) | " + " | ".join(f"{g:g} nats" for g in gains)
          + " | 'pose' warnings |")
    print("|---|---|" + "---|" * len(gains) + "---|")
    for name in ("clean", "shanks mirrored"):
        r = w[name]
        print(f"| {name} | {100 * r['default']:.1f} % | " + " | ".join(f"{100 * r[g]:.1f} %" for g in gains)
              + f" | {r['pose flags']} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*", help="evaluation BVH files (for the selfcheck part)")
    ap.add_argument("--part", default="all", choices=["multiview", "selfcheck", "all"])
    ap.add_argument("--frames", type=int, default=300, help="selfcheck: first frames of each clip at 30 fps")
    ap.add_argument("--mv-frames", type=int, default=150, help="multiview: frames of the built-in clips")
    ap.add_argument("--draws", type=int, default=1, help="selfcheck: random sides per clip")
    ap.add_argument("--gains", default="5,10,15", help="selfcheck: thresholds in nats")
    ap.add_argument("--no-walk", action="store_true", help="selfcheck: skip the built-in walk's estimate")
    ap.add_argument("--prior", default=None, help="a pose prior file instead of the shipped one")
    args = ap.parse_args(argv)
    if args.prior is not None:
        motion_prior.DEFAULT_PATH = args.prior
        motion_prior.load_default.cache_clear()
    t0 = time.process_time()
    if args.part in ("multiview", "all"):
        run_multiview(args.mv_frames)
        print()
    if args.part in ("selfcheck", "all"):
        run_selfcheck(args.clips, args.frames, args.draws, [float(g) for g in args.gains.split(",")],
                      not args.no_walk)
    print(f"\n{time.process_time() - t0:.0f} s CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())
