"""The pose lifter against the pose prior: how often each reads a limb bone's depth sign right.

Every clip (the shared evaluation clips and the built-in walk and run, split into tune / report halves as in
``bench/robust_bench.py``; none of them is training data) is sampled every third frame of its first
10 s at 30 fps and seen from a random view per frame (any heading, elevation -15..40 degrees, a slight
roll, 3-12 m away, perspective, the true joints).  For every limb bone clearly out of the picture's
plane (depth over length above 0.3):

* ``lifter``: the shipped :class:`core.motion_prior.PoseLifter` reads the picture alone and says which
  way the bone points in depth;
* ``prior``: the shipped :class:`core.motion_prior.PosePrior` compares the true pose with the one with
  that bone's depth flipped, every other bone as it truly is (an easier question: the prior is told
  the rest of the pose).

    python bench/lifter_bench.py ../shared/data/bvh/*.bvh --half report [--lifter FILE]
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.robust_bench import _case_rng, half_of  # noqa: E402
from core.motion_prior import PoseLifter, load_default, load_default_lifter  # noqa: E402
from core.motion_prior.evaluation import LIMB_BONES  # noqa: E402
from core.motion_prior.features import bone_vectors  # noqa: E402
from core.motion_prior.train_lifter import view_rotations  # noqa: E402
from core.synthetic.motion import load_motion  # noqa: E402

SLANT = 0.3


def run_clip(clip: str, lifter, prior) -> dict:
    rng = _case_rng(clip, "lifter", 0)
    joints = load_motion(clip, fps=30.0, max_frames=300).joints[::3]
    n = len(joints)
    cam = np.einsum("nab,njb->nja", view_rotations(rng, n), joints - joints[:, :1])
    cam[..., 2] += np.exp(rng.uniform(np.log(3.0), np.log(12.0), n))[:, None]
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    true = bone_vectors(cam)
    limbs = np.array(LIMB_BONES)
    clear = (np.abs(true[..., 2]) / np.linalg.norm(true, axis=-1))[:, limbs] > SLANT
    lifted = lifter.bone_directions(rays)
    by_lifter = (np.sign(lifted[..., 2]) == np.sign(true[..., 2]))[:, limbs][clear]
    by_prior = (prior.flip_gains(cam) < 0)[:, limbs][clear]
    return {"bones": int(clear.sum()), "lifter": float(by_lifter.mean()), "prior": float(by_prior.mean())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clips", nargs="*")
    ap.add_argument("--half", default="report", choices=["tune", "report", "both"])
    ap.add_argument("--lifter", default=None, help="a lifter file instead of the shipped one")
    args = ap.parse_args(argv)
    lifter = PoseLifter.load(args.lifter) if args.lifter else load_default_lifter()
    prior = load_default()
    clips = [c for c in list(args.clips) + ["builtin:walk", "builtin:run"]
             if args.half == "both" or half_of(c) == args.half]
    rows = []
    for clip in clips:
        r = run_clip(clip, lifter, prior)
        rows.append(r)
        print(f"{os.path.basename(clip)}: {r['bones']} limb bones, lifter {100 * r['lifter']:.1f} %, "
              f"prior {100 * r['prior']:.1f} %", flush=True)
    print(f"\n| {args.half} half, {len(rows)} clips | lifter (the picture alone) | prior (told the rest of the pose) |")
    print("|---|---|---|")
    print(f"| limb bones' depth sign right, mean of clips | {100 * np.mean([r['lifter'] for r in rows]):.1f} % "
          f"| {100 * np.mean([r['prior'] for r in rows]):.1f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
