"""The pose lifter against the pose prior: how often each reads a limb bone's depth sign right.

Every clip (the shared evaluation clips and the built-in walk and run, split into tune / report halves as in
``bench/robust_bench.py``; none of them is training data) is sampled every third frame of its first
10 s at 30 fps and seen from a random view per frame (any heading, elevation -15..40 degrees, a slight
roll, 3-12 m away, perspective, the true joints).  For every limb bone clearly out of the picture's
plane (depth over length above 0.3):

* ``lifter``: the shipped :class:`core.motion_prior.PoseLifter` reads the picture alone and says which
  way the bone points in depth;
* ``video``: the shipped video lifter (``load_video_lifter``) reads the same picture with the frames
  around it (0.4 s each way at 30 fps, the same view, the clip's own motion; ``--held``: the same
  picture again, a person holding the pose) and says the same;
* ``prior``: the shipped :class:`core.motion_prior.PosePrior` compares the true pose with the one with
  that bone's depth flipped, every other bone as it truly is (an easier question: the prior is told
  the rest of the pose).

    python bench/lifter_bench.py ../shared/data/bvh/*.bvh --half report [--lifter FILE] [--video-lifter FILE]
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.motion_prior import PoseLifter, load_default, load_default_lifter, load_video_lifter  # noqa: E402
from core.motion_prior.evaluation import LIMB_BONES  # noqa: E402
from core.motion_prior.features import bone_vectors  # noqa: E402
from core.motion_prior.train_lifter import view_rotations  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402

SLANT = 0.3


FPS = 30.0
#: Frames each way the video lifter is given around a picture (0.4 s at 30 fps: its widest tap).
AROUND = 12


def run_clip(clip: str, lifter, prior, video=None, held: bool = False) -> dict:
    rng = _case_rng(clip, "lifter", 0)
    every = load_motion(clip, fps=FPS, max_frames=300).joints
    centre = np.arange(0, len(every), 3)
    joints = every[centre]
    n = len(joints)
    R = view_rotations(rng, n)
    cam = np.einsum("nab,njb->nja", R, joints - joints[:, :1])
    dist = np.exp(rng.uniform(np.log(3.0), np.log(12.0), n))
    cam[..., 2] += dist[:, None]
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    true = bone_vectors(cam)
    limbs = np.array(LIMB_BONES)
    clear = (np.abs(true[..., 2]) / np.linalg.norm(true, axis=-1))[:, limbs] > SLANT
    lifted = lifter.bone_directions(rays)
    by_lifter = (np.sign(lifted[..., 2]) == np.sign(true[..., 2]))[:, limbs][clear]
    by_prior = (prior.flip_gains(cam) < 0)[:, limbs][clear]
    out = {"bones": int(clear.sum()), "lifter": float(by_lifter.mean()), "prior": float(by_prior.mean())}
    if video is not None:
        read = np.empty_like(lifted)
        for k, c in enumerate(centre):
            idx = np.clip(np.arange(c - AROUND, c + AROUND + 1), 0, len(every) - 1)
            if held:                                    # the person holds the pose: every frame the same
                idx = np.full_like(idx, c)
            win = np.einsum("ab,njb->nja", R[k], every[idx] - every[c, :1])   # the centre frame's pelvis fixed
            win[..., 2] += dist[k]
            read[k] = video.bone_directions(win / np.linalg.norm(win, axis=-1, keepdims=True), FPS)[AROUND]
        out["video"] = float((np.sign(read[..., 2]) == np.sign(true[..., 2]))[:, limbs][clear].mean())
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--lifter", default=None, help="a lifter file instead of the shipped one")
    ap.add_argument("--video-lifter", default=None, help="a video lifter file instead of the shipped one")
    ap.add_argument("--held", action="store_true",
                    help="the video lifter's frames around each picture are that picture again (a held pose)")
    args = ap.parse_args(argv)
    lifter = PoseLifter.load(args.lifter) if args.lifter else load_default_lifter()
    video = PoseLifter.load(args.video_lifter) if args.video_lifter else load_video_lifter()
    if not video.temporal:
        video = None
    prior = load_default()
    clips = [c for c in list(args.clips) + ["builtin:walk", "builtin:run"]
             if args.half == "both" or half_of(c) == args.half]
    rows = []
    for clip in clips:
        r = run_clip(clip, lifter, prior, video, held=args.held)
        rows.append(r)
        seen = f", video lifter {100 * r['video']:.1f} %" if video is not None else ""
        print(f"{os.path.basename(clip)}: {r['bones']} limb bones, lifter {100 * r['lifter']:.1f} %{seen}, "
              f"prior {100 * r['prior']:.1f} %", flush=True)
    around = "a held pose" if args.held else "0.4 s each way"
    cols = ["lifter (the picture alone)"] + ([f"video lifter ({around})"] if video is not None else []) \
        + ["prior (told the rest of the pose)"]
    keys = ["lifter"] + (["video"] if video is not None else []) + ["prior"]
    print(f"\n| {args.half} half, {len(rows)} clips | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    print("| limb bones' depth sign right, mean of clips | "
          + " | ".join(f"{100 * np.mean([r[k] for r in rows]):.1f} %" for k in keys) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
