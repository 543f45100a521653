"""Training the pose lifter (:mod:`.lifter`) from BVH folders (``python -m core train-lifter DIR... --out FILE``).

Every training pose is filmed from views drawn afresh for every batch, so the network never sees the
same picture twice and learns no camera:

* the pose: a frame of a clip (:func:`.train.clip_poses`, the same clips and refusals as the pose
  prior), or the same frame mirrored left for right; in half of the pictures some of its limbs are
  another frame's, turned into this body's frame (:func:`mixed_limbs`), so the network meets more poses
  than the clips hold and reads each limb rather than whole poses it has learnt;
* its proportions: every length class scaled by its own factor (:data:`LENGTH_JITTER`), so that the
  network reads the pose, not the capture rig's proportions (the evaluation clips' rigs differ);
* its rig: the pelvis, spine, thorax and shoulder joints moved in the body's frame
  (:data:`RIG_JITTER_M`): where a rig puts them is its own convention (the CMU rig's pelvis sits lower
  than the hips, other rigs' level with them), and a network that learnt one rig's placement reads
  another's as a different pose;
* the view: any heading, an elevation from :data:`ELEVATION_DEG`, a roll about the line of sight, a
  distance from :data:`DISTANCE_M` (the perspective of a close camera shows in the picture);
* the picture: Gaussian noise on the joints (:data:`NOISE`, relative to the joints' spread), larger at
  the extremities (:data:`NOISE_WEIGHT`, as a detector is least sure of them), and now and then one
  joint thrown further (:data:`OUTLIER_RATE`, :data:`OUTLIER`: a detector's gross error or a gap filled
  in time), so that the network reads a detector's tracks, not only exact ones.

A temporal lifter (``--taps``) is trained on windows of consecutive frames (:class:`Sequences`,
:func:`sample_windows`): the window played at a pace of its own (:data:`SPEED_LOG`), one body, rig and view
for the whole window, a limb recombined from another clip's window over the whole window, the picture's
noise drawn per frame.

Adam on the mean squared error of the pelvis-relative joints, with a fixed seed: the same clips
give the same file.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from ..skeleton import JOINT_INDEX, JOINTS, LIMBS, SEGMENT_CLASS
from ..timebase.frames import frames_between
from .features import body_frame, bone_vectors, joints_from_bones, mirrored_left_right
from .lifter import INPUT_JOINTS, N_INPUTS, N_OUTPUTS, OUTPUT_BONES, PoseLifter, normalised_view
from .train import TRAIN_FPS, add_training_arguments, output_path, training_clips

WIDTH = 256
HIDDEN_LAYERS = 3
STEPS = 8000
BATCH = 512
LEARNING_RATE = 1e-3
FINAL_LEARNING_RATE = 5e-5
SEED = 20261
#: The lifter is the mean of this many networks, trained alike from the seeds ``SEED``, ``SEED + 1``, ...
#: (:meth:`.lifter.PoseLifter.averaged`): each one's sign errors are partly its own, and the mean's
#: directions are steadier (docs/motion_prior.md, "Four networks averaged").
MEMBERS = 4
#: Standard deviation of the factor on each length class.
LENGTH_JITTER = 0.08
ELEVATION_DEG = (-15.0, 40.0)
ROLL_DEG = 8.0
DISTANCE_M = (2.5, 20.0)
#: Standard deviations (metres; left, up, forward in the body's frame) of the moves of the pelvis, the
#: spine and thorax joints, and the shoulders (mirrored left for right).
RIG_JITTER_M = {"pelvis": (0.02, 0.06, 0.04), "spine": (0.01, 0.04, 0.03), "thorax": (0.01, 0.04, 0.03),
                "shoulder": (0.03, 0.05, 0.04)}
#: Upper end of the joints' noise, a uniform draw per picture, in units of the joints' spread.
NOISE = 0.03
#: Noise multiplier per input joint (:data:`.lifter.INPUT_JOINTS`): wrists and ankles x2, elbows and knees x1.5.
NOISE_WEIGHT = np.array([2.0 if name in ("l_wrist", "r_wrist", "l_ankle", "r_ankle")
                         else 1.5 if name in ("l_elbow", "r_elbow", "l_knee", "r_knee") else 1.0
                         for name in (JOINTS[j] for j in INPUT_JOINTS)])
#: Share of pictures with one joint thrown, and how far (standard deviation, in units of the spread).
OUTLIER_RATE = 0.1
OUTLIER = 0.15
#: Share of pictures whose limbs are recombined (:func:`mixed_limbs`), and each limb's chance there.
MIX_RATE = 0.5
MIX_LIMB = 0.5

_CLASS = np.array(SEGMENT_CLASS)
_UP = np.array([0.0, 1.0, 0.0])
_J = JOINT_INDEX
_SEG = {name: _J[name] - 1 for name in ("spine", "thorax", "neck", "l_hip", "r_hip", "l_shoulder", "r_shoulder")}
_OUT = np.array(OUTPUT_BONES)


def pose_bank(clip_joints: list[np.ndarray], mirror: bool = True) -> np.ndarray:
    """(N, 16, 3) bone vectors of every training frame (and its left-right mirror)."""
    joints = [j for j in clip_joints if len(j)]
    if mirror:
        joints = joints + [mirrored_left_right(j) for j in joints]
    bones = bone_vectors(np.concatenate(joints))
    return bones[np.isfinite(bones).all(axis=(1, 2))]


def rig_jitter(bones: np.ndarray, rng: np.random.Generator, per: int = 1) -> np.ndarray:
    """``bones`` (n, 16, 3) with the pelvis, spine, thorax and shoulder joints moved (:data:`RIG_JITTER_M`);
    each run of ``per`` consecutive poses (one window's frames) moved alike."""
    n = len(bones)
    frame = body_frame(bones)                                              # rows left, up, forward
    out = bones.copy()

    def move(name):
        return np.repeat(rng.standard_normal((n // per, 3)) * np.array(RIG_JITTER_M[name]), per, axis=0)

    def world(local):
        return np.einsum("nba,nb->na", frame, local)

    p = world(move("pelvis"))                    # the pelvis moves: its bones to the hips and spine shorten
    for name in ("l_hip", "r_hip", "spine"):
        out[:, _SEG[name]] -= p
    s = world(move("spine"))
    out[:, _SEG["spine"]] += s
    out[:, _SEG["thorax"]] -= s
    t = world(move("thorax"))
    out[:, _SEG["thorax"]] += t
    for name in ("neck", "l_shoulder", "r_shoulder"):
        out[:, _SEG[name]] -= t
    sh = move("shoulder")
    out[:, _SEG["l_shoulder"]] += world(sh)
    out[:, _SEG["r_shoulder"]] += world(sh * np.array([-1.0, 1.0, 1.0]))
    return out


def view_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3, 3) world-to-camera rotations (rows: the camera's x right, y down, z forward) looking at the
    pelvis from a random heading, elevation and roll."""
    az = rng.uniform(0.0, 2.0 * np.pi, n)
    el = np.radians(rng.uniform(*ELEVATION_DEG, n))
    roll = np.radians(rng.normal(0.0, ROLL_DEG, n))
    z = np.stack([np.cos(el) * np.sin(az), -np.sin(el), np.cos(el) * np.cos(az)], axis=1)
    x = np.cross(z, _UP)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)
    c, s = np.cos(roll)[:, None], np.sin(roll)[:, None]
    x, y = c * x + s * y, -s * x + c * y
    return np.stack([x, y, z], axis=1)


#: Each limb's upper and lower bone (segment indices: a joint's own segment is its index minus one).
_LIMB_SEGMENTS = [tuple(j - 1 for j in LIMBS[limb][1:]) for limb in ("l_arm", "l_leg", "r_arm", "r_leg")]


def mixed_limbs(bones: np.ndarray, bank: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``bones`` (n, 16, 3) with, in :data:`MIX_RATE` of the poses, each limb (upper and lower bone) taken
    with chance :data:`MIX_LIMB` from another frame of ``bank``, turned from that body's frame into this
    one's: more poses than the clips hold, so that the network reads each limb, not whole poses learnt."""
    n = len(bones)
    out = bones.copy()
    frame = body_frame(bones)
    mix = rng.random(n) < MIX_RATE
    for segs in _LIMB_SEGMENTS:
        pick = np.flatnonzero(mix & (rng.random(n) < MIX_LIMB))
        if pick.size == 0:
            continue
        donor = bank[rng.integers(len(bank), size=pick.size)]
        local = np.einsum("nab,nsb->nsa", body_frame(donor), donor[:, list(segs)])
        out[np.ix_(pick, list(segs))] = np.einsum("nba,nsb->nsa", frame[pick], local)
    return out


def sample_batch(bank: np.ndarray, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(inputs (n, N_INPUTS), targets (n, N_OUTPUTS)): ``n`` training poses filmed as the module docstring says."""
    bones = mixed_limbs(bank[rng.integers(len(bank), size=n)], bank, rng)
    scale = 1.0 + LENGTH_JITTER * rng.standard_normal((n, int(_CLASS.max()) + 1))
    bones = rig_jitter(bones * scale[:, _CLASS, None], rng)
    rel = joints_from_bones(bones)                                        # pelvis at the origin
    cam = np.einsum("nab,njb->nja", view_rotations(rng, n), rel)
    dist = np.exp(rng.uniform(*np.log(DISTANCE_M), n))
    cam[..., 2] += dist[:, None]
    # the run time's input (the picture turned to look along the pelvis's ray, which it already does up
    # to the roll), from the points themselves: a ray's direction is all that counts
    x, turn, spread = normalised_view(cam)
    x = x.reshape(n, -1, 2)
    x = x + rng.standard_normal(x.shape) * rng.uniform(0.0, NOISE, n)[:, None, None] * NOISE_WEIGHT[None, :, None]
    thrown = np.flatnonzero(rng.random(n) < OUTLIER_RATE)
    x[thrown, rng.integers(x.shape[1], size=thrown.size)] += rng.standard_normal((thrown.size, 2)) * OUTLIER
    v = np.einsum("nab,njb->nja", turn, cam)
    target = bone_vectors(v)[:, _OUT] / (v[:, :1, 2:3] * spread[:, None, None])
    return x.reshape(n, N_INPUTS), target.reshape(n, N_OUTPUTS)


#: A temporal lifter's window is played at a speed drawn from exp(+-SPEED_LOG): people move at their own pace.
SPEED_LOG = float(np.log(1.25))


class Sequences:
    """Every training clip's bone vectors (and its left-right mirror's), end to end, with each frame's
    clip bounds: windows of frames around any frame for a temporal lifter."""

    def __init__(self, clip_joints: list[np.ndarray], mirror: bool = True):
        clips = [j for j in clip_joints if len(j)]
        if mirror:
            clips = clips + [mirrored_left_right(j) for j in clips]
        bones, lo, hi, start = [], [], [], 0
        for j in clips:
            b = bone_vectors(j)
            b = b[np.isfinite(b).all(axis=(1, 2))]
            bones.append(b)
            lo.append(np.full(len(b), start))
            hi.append(np.full(len(b), start + len(b) - 1))
            start += len(b)
        self.bones = np.concatenate(bones)
        self.lo = np.concatenate(lo)
        self.hi = np.concatenate(hi)

    def __len__(self) -> int:
        return len(self.bones)

    def window(self, centre: np.ndarray, speed: np.ndarray, taps_s) -> np.ndarray:
        """(n, T, 16, 3) the bones at ``taps_s`` seconds (played at ``speed``) around frames ``centre``
        (n,), linear between frames and held at a clip's ends."""
        p = centre[:, None] + np.asarray(taps_s)[None, :] * TRAIN_FPS * speed[:, None]
        i0, i1, w = frames_between(p, self.lo[centre][:, None], self.hi[centre][:, None])
        w = w[..., None, None]
        return self.bones[i0] * (1.0 - w) + self.bones[i1] * w


def sample_windows(seq: Sequences, rng: np.random.Generator, n: int, taps_s) -> tuple[np.ndarray, np.ndarray]:
    """(inputs (n, T x N_INPUTS), targets (n, N_OUTPUTS)): ``n`` windows of ``T`` = len(taps_s) frames,
    each filmed as :func:`sample_batch` films a pose (one view, proportions and rig for the whole window,
    the picture's noise drawn per frame); the target is the bones at tap 0 s."""
    taps = tuple(taps_s)
    T = len(taps)
    mid = taps.index(0.0)
    speed = np.exp(rng.uniform(-SPEED_LOG, SPEED_LOG, n))
    bones = seq.window(rng.integers(len(seq), size=n), speed, taps)
    mix = rng.random(n) < MIX_RATE
    donor = seq.window(rng.integers(len(seq), size=n), speed, taps)
    frame = body_frame(bones.reshape(-1, 16, 3)).reshape(n, T, 3, 3)
    dframe = body_frame(donor.reshape(-1, 16, 3)).reshape(n, T, 3, 3)
    for segs in _LIMB_SEGMENTS:
        pick = np.flatnonzero(mix & (rng.random(n) < MIX_LIMB))
        if pick.size == 0:
            continue
        segs = list(segs)
        local = np.einsum("ntab,ntsb->ntsa", dframe[pick], donor[pick][:, :, segs])
        bones[pick[:, None], :, segs] = np.einsum("ntba,ntsb->ntsa", frame[pick], local).transpose(0, 2, 1, 3)
    scale = 1.0 + LENGTH_JITTER * rng.standard_normal((n, int(_CLASS.max()) + 1))
    bones = bones * scale[:, None, _CLASS, None]
    flat = rig_jitter(bones.reshape(n * T, 16, 3), rng, per=T)
    rel = joints_from_bones(flat)
    cam = np.einsum("nab,njb->nja", np.repeat(view_rotations(rng, n), T, axis=0), rel)
    cam[..., 2] += np.repeat(np.exp(rng.uniform(*np.log(DISTANCE_M), n)), T)[:, None]
    x, turn, spread = normalised_view(cam)
    x = x.reshape(n * T, -1, 2)
    x = x + rng.standard_normal(x.shape) * rng.uniform(0.0, NOISE, n * T)[:, None, None] * NOISE_WEIGHT[None, :, None]
    thrown = np.flatnonzero(rng.random(n * T) < OUTLIER_RATE)
    x[thrown, rng.integers(x.shape[1], size=thrown.size)] += rng.standard_normal((thrown.size, 2)) * OUTLIER
    c = np.arange(n) * T + mid
    v = np.einsum("nab,njb->nja", turn[c], cam[c])
    target = bone_vectors(v)[:, _OUT] / (v[:, :1, 2:3] * spread[c][:, None, None])
    return x.reshape(n, T * N_INPUTS), target.reshape(n, N_OUTPUTS)


def _init(rng, width: int, layers: int, inputs: int = N_INPUTS):
    sizes = [inputs] + [width] * layers + [N_OUTPUTS]
    ws = [rng.standard_normal((a, b)) * np.sqrt(2.0 / a) for a, b in zip(sizes[:-1], sizes[1:])]
    ws[-1] *= 0.1
    bs = [np.zeros(b) for b in sizes[1:]]
    return ws, bs


def fit(bank, *, steps: int = STEPS, width: int = WIDTH, layers: int = HIDDEN_LAYERS,
        batch: int = BATCH, seed: int = SEED, taps_s=(0.0,), progress=None) -> tuple[list, list, float]:
    """(weights, biases, final loss): Adam on :func:`sample_batch` pictures of ``bank`` (an array of
    poses), or on :func:`sample_windows` of it (a :class:`Sequences`) for ``taps_s`` of more than one tap."""
    rng = np.random.default_rng(seed)
    temporal = len(taps_s) > 1
    ws, bs = _init(rng, width, layers, N_INPUTS * len(taps_s))
    params = ws + bs
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    b1, b2, eps = 0.9, 0.999, 1e-8
    decay = (FINAL_LEARNING_RATE / LEARNING_RATE) ** (1.0 / max(steps, 1))
    loss_avg = None
    for step in range(1, steps + 1):
        x, t = sample_windows(bank, rng, batch, taps_s) if temporal else sample_batch(bank, rng, batch)
        acts = [x]
        h = x
        for i in range(len(ws)):
            h = h @ ws[i] + bs[i]
            if i < len(ws) - 1:
                h = np.maximum(h, 0.0)
            acts.append(h)
        err = acts[-1] - t
        loss = float(np.mean(err * err))
        loss_avg = loss if loss_avg is None else 0.99 * loss_avg + 0.01 * loss
        g = 2.0 * err / err.size
        gw, gb = [None] * len(ws), [None] * len(ws)
        for i in range(len(ws) - 1, -1, -1):
            gw[i] = acts[i].T @ g
            gb[i] = g.sum(axis=0)
            if i > 0:
                g = (g @ ws[i].T) * (acts[i] > 0)
        lr = LEARNING_RATE * decay ** step
        for k, (p, gp) in enumerate(zip(params, gw + gb)):
            m[k] = b1 * m[k] + (1 - b1) * gp
            v[k] = b2 * v[k] + (1 - b2) * gp * gp
            p -= lr * (m[k] / (1 - b1 ** step)) / (np.sqrt(v[k] / (1 - b2 ** step)) + eps)
        if progress is not None and step % 500 == 0:
            progress(step / steps, f"step {step} of {steps}, loss {loss_avg:.4f}")
    return ws, bs, float(loss_avg)


def train(clip_joints: list[np.ndarray], *, steps: int = STEPS, width: int = WIDTH, layers: int = HIDDEN_LAYERS,
          seed: int = SEED, members: int = MEMBERS, taps_s=(0.0,), meta: dict | None = None,
          progress=None) -> PoseLifter:
    """A :class:`PoseLifter` from clips of canonical joints: the mean of ``members`` networks (:data:`MEMBERS`),
    each reading the frames ``taps_s`` seconds around the one it answers (one tap, 0 s: a single picture)."""
    taps_s = tuple(float(t) for t in taps_s)
    if 0.0 not in taps_s:
        raise InputError("the lifter's taps must include 0 s, the frame it answers")
    bank = pose_bank(clip_joints) if len(taps_s) == 1 else Sequences(clip_joints)
    if len(bank) < 100:
        raise InputError("too few frames to train a pose lifter")
    if members < 1:
        raise InputError(f"a lifter needs at least one network, got {members}")
    nets, record = [], []
    for k in range(members):
        tell = None
        if progress is not None:
            def tell(frac, msg, k=k):
                progress((k + frac) / members, msg if members == 1 else f"network {k + 1} of {members}: {msg}")
        ws, bs, loss = fit(bank, steps=steps, width=width, layers=layers, seed=seed + k, taps_s=taps_s,
                           progress=tell)
        nets.append(PoseLifter(ws, bs, {"taps_s": list(taps_s)}))
        record.append({"seed": seed + k, "final_loss": loss})
    info = {"width": width, "hidden_layers": layers, "steps": steps, "batch": BATCH, "seed": seed,
            "members": record, "final_loss": float(np.mean([r["final_loss"] for r in record])),
            "training_frames": int(sum(len(j) for j in clip_joints)), "fps": TRAIN_FPS,
            "length_jitter": LENGTH_JITTER, "elevation_deg": list(ELEVATION_DEG), "roll_deg": ROLL_DEG,
            "distance_m": list(DISTANCE_M), "noise": NOISE,
            "noise_weight": NOISE_WEIGHT.tolist(), "outlier_rate": OUTLIER_RATE, "outlier": OUTLIER,
            "mix_rate": MIX_RATE, "mix_limb": MIX_LIMB,
            "rig_jitter_m": {k: list(v) for k, v in RIG_JITTER_M.items()}}
    if len(taps_s) > 1:
        info.update({"taps_s": list(taps_s), "speed_log": SPEED_LOG})
    info.update(meta or {})
    if members == 1:
        return PoseLifter(nets[0].weights, nets[0].biases, info)
    return PoseLifter.averaged(nets, info)


def train_from_files(inputs: list[str], *, steps: int = STEPS, members: int = MEMBERS, taps_s=(0.0,),
                     progress=None, sources=(), licences=()) -> PoseLifter:
    """Train on every ``.bvh`` of ``inputs`` (:func:`.train.collect_clips`); the result records the clips."""
    joints, meta = training_clips(inputs, sources=sources, licences=licences)
    return train(joints, steps=steps, members=members, taps_s=taps_s, meta=meta, progress=progress)


def add_arguments(parser) -> None:
    add_training_arguments(parser, "lifter")
    parser.add_argument("--steps", type=int, default=STEPS, help="training steps (default %(default)s)")
    parser.add_argument("--members", type=int, default=MEMBERS,
                        help="networks trained and averaged into the lifter (default %(default)s)")
    parser.add_argument("--taps", default="0",
                        help="comma-separated seconds around the answered frame the lifter reads "
                             "(default %(default)s: one picture; e.g. -0.4,-0.2,0,0.2,0.4)")
    parser.add_argument("--float16", action="store_true",
                        help="store the weights as 16-bit floats (half the file; read back as 32-bit)")


def run(args) -> int:
    t0 = time.perf_counter()
    out = output_path(args.out, "lifter")
    try:
        taps = tuple(float(t) for t in args.taps.split(","))
    except ValueError:
        raise InputError(f"--taps takes comma-separated seconds, got {args.taps!r}") from None
    lifter = train_from_files(args.inputs, steps=args.steps, members=args.members, taps_s=taps, sources=args.source,
                              licences=args.licence,
                              progress=lambda f, msg: print(f"  {msg}", flush=True))
    lifter.save(out, half=args.float16)
    print(f"pose lifter: {len(lifter.meta['clips'])} clips, {lifter.meta['training_frames']} frames, loss "
          f"{lifter.meta['final_loss']:.4f} -> {out} ({out.stat().st_size / 1024:.0f} KB, "
          f"{time.perf_counter() - t0:.1f} s)")
    return 0
