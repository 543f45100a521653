"""The pose prior on held-out CMU subjects: how well it scores unseen poses and picks depth signs.

Every fold trains on the training clips of all subjects but one and tests on that subject's clips
(../shared/data/train/cmu, whole subjects held out).  Per model (a single Gaussian, and mixtures of
``--components``):

* held-out log-likelihood per frame (nats, higher is better);
* sign accuracy: for every held-out frame seen from ``--views`` random directions (heading anywhere,
  elevation within +-20 degrees, orthographic), and for every bone, whether the prior scores the true
  pose above the one with that bone's depth sign flipped (everything else as it is: the true 2D).
  Reported over bones clearly out of the picture's plane (depth over length above 0.3; nearer the
  plane both choices are nearly the same pose) and for the four limbs' 8 bones alone.

    python bench/prior_bench.py [--components 1,4,8,16,32] [--holdout 6,7] [--views 4]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from core.motion_prior.features import bone_vectors  # noqa: E402
from core.motion_prior.train import TRAIN_FPS, clip_poses, collect_clips, train  # noqa: E402
from core.skeleton import LIMBS, SEGMENTS  # noqa: E402

CMU = Path(__file__).resolve().parents[2] / "shared" / "data" / "train" / "cmu"
LIMB_BONES = np.array([k for k, (_, c) in enumerate(SEGMENTS) if any(c in js[1:] for js in LIMBS.values())])


def random_views(n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, 3, 3) rotations world (Y up) -> camera (x right, y down, z forward): heading anywhere, elevation +-20."""
    yaw = rng.uniform(-np.pi, np.pi, n)
    pitch = np.radians(rng.uniform(-20, 20, n))
    out = np.empty((n, 3, 3))
    for i in range(n):
        cy, sy, cp, sp = np.cos(yaw[i]), np.sin(yaw[i]), np.cos(pitch[i]), np.sin(pitch[i])
        ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        rx = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
        flip = np.diag([1.0, -1.0, -1.0])            # world Y up -> camera y down, looking along +z
        out[i] = rx @ flip @ ry
    return out


def sign_accuracy(prior, joints: np.ndarray, views: int, rng) -> tuple[float, float, int]:
    """(accuracy over bones out of plane, the same for limb bones, count) on poses (F, 17, 3)."""
    hits, limb_hits, total, limb_total = 0, 0, 0, 0
    for _ in range(views):
        R = random_views(len(joints), rng)
        cam = np.einsum("fab,fjb->fja", R, joints)
        gains = prior.flip_gains(cam)                                 # > 0: the flip is preferred
        b = bone_vectors(cam)
        out = np.abs(b[..., 2]) / np.linalg.norm(b, axis=-1) > 0.3
        right = gains < 0
        hits += int(np.sum(right & out))
        total += int(np.sum(out))
        limb_hits += int(np.sum((right & out)[:, LIMB_BONES]))
        limb_total += int(np.sum(out[:, LIMB_BONES]))
    return hits / max(total, 1), limb_hits / max(limb_total, 1), total


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--components", default="1,4,8,16,32")
    ap.add_argument("--holdout", default="6,7", help="subjects held out, one fold each")
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--reg", type=float, default=None)
    ap.add_argument("--no-mirror", action="store_true")
    ap.add_argument("--data", default=str(CMU), help="the training clips (default %(default)s)")
    args = ap.parse_args(argv)
    if not Path(args.data).is_dir():
        print(f"training clips not found at {args.data}")
        return 1
    files = collect_clips([args.data])
    clips = {f.name: clip_poses(f, TRAIN_FPS) for f in files}
    subject = {name: int(name.split("_")[0]) for name in clips}
    print("| held out | model | train frames | test frames | log-lik / frame | sign acc. (out of plane) | "
          "limb bones | seconds |")
    print("|---|---|---|---|---|---|---|---|")
    for held in (int(s) for s in args.holdout.split(",")):
        tr = [clips[n] for n in clips if subject[n] != held]
        te = np.concatenate([clips[n] for n in clips if subject[n] == held])
        for k in (int(c) for c in args.components.split(",")):
            t0 = time.perf_counter()
            kw = {} if args.reg is None else {"reg": args.reg}
            prior = train(tr, components=k, mirror=not args.no_mirror, **kw)
            sec = time.perf_counter() - t0
            ll = float(np.mean(prior.log_likelihood(te)))
            acc, limb, count = sign_accuracy(prior, te, args.views, np.random.default_rng(held))
            name = "single Gaussian" if k == 1 else f"mixture of {k}"
            print(f"| subject {held} | {name} | {sum(len(c) for c in tr)} | {len(te)} | {ll:.1f} | "
                  f"{100 * acc:.1f} % | {100 * limb:.1f} % | {sec:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
