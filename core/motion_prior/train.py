"""Training the pose prior from BVH folders (``python -m core train-prior DIR... --out FILE``).

Steps: every ``*.bvh`` of the folders (sorted, so the run is the same on every machine) read and
mapped to the canonical 17 joints (:func:`core.synthetic.motion.load_motion`, which also resamples:
:data:`TRAIN_FPS`); each frame's features (:mod:`.features`), and those of the frame mirrored left
for right (:func:`.features.mirrored_left_right`); a Gaussian mixture fitted by EM from a k-means++
start with a fixed seed; the features' rate of change gives the temporal term.  The body frame takes
out the heading, so no random heading is added.

Evaluation clips are refused: anything under the project's ``../shared/data/bvh`` (the accuracy
tables' clips) and CMU subjects 01 and 131 by file name.  The file written records every clip used
(name, frames, SHA-256) and where the data came from (``source``, ``licence``).
"""

from __future__ import annotations

import hashlib
import re
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.file_io import check_output_file
from .features import LIMB_BONES, mirrored_left_right, pose_features
from .model import PosePrior, component_log_densities

#: Frames per second the clips are resampled to (60 fps mocap is nearly twice the same pose).
TRAIN_FPS = 30.0
#: Mixture components and the variance added to each covariance's diagonal (chosen on held-out
#: subjects, docs/motion_prior.md).
COMPONENTS = 8
REGULARISATION = 0.03
EM_ITERATIONS = 40
SEED = 20260
SOURCE = "CMU Graphics Lab Motion Capture Database, mocap.cs.cmu.edu"
LICENCE = ("free to use, also inside commercially sold products; not to be resold as data "
           "(the CMU database's terms)")

#: The record's ``source`` for clips of several databases (``--licence`` given) without ``--source``.
MIXED_SOURCE = "several motion-capture databases: see the folders and the licence"

_EVALUATION_NAME = re.compile(r"^0*(1|131)_\d+", re.IGNORECASE)


def evaluation_dir() -> Path:
    """The project's evaluation clips, ``<repo>/../shared/data/bvh``."""
    return Path(__file__).resolve().parents[3] / "shared" / "data" / "bvh"


def refuse_evaluation(path: Path) -> None:
    """Raise :class:`InputError` if ``path`` is an evaluation clip (module docstring)."""
    resolved = path.resolve()
    parts = resolved.parts
    under_eval = any(parts[i:i + 3] == ("shared", "data", "bvh") for i in range(len(parts) - 2))
    try:
        resolved.relative_to(evaluation_dir().resolve())
        under_eval = True
    except ValueError:
        pass
    if under_eval:
        raise InputError(f"{path}: the clips under shared/data/bvh are evaluation data; a prior may not be trained "
                         "on them")
    if _EVALUATION_NAME.match(resolved.name):
        raise InputError(f"{path}: CMU subjects 01 and 131 are evaluation data; a prior may not be trained on them")
    if resolved.is_file() and sha256(resolved) in _evaluation_hashes():
        raise InputError(f"{path}: the same file as an evaluation clip of shared/data/bvh; a prior may not be trained "
                         "on it")


@lru_cache(maxsize=1)
def _evaluation_hashes() -> frozenset:
    """SHA-256 of every evaluation clip (none when the folder is not there), so that a copy under another
    name is refused too."""
    folder = evaluation_dir()
    if not folder.is_dir():
        return frozenset()
    return frozenset(sha256(p) for p in folder.glob("*.bvh"))


def collect_clips(inputs: list[str]) -> list[Path]:
    """The ``.bvh`` files of ``inputs`` (folders, searched recursively, or files), sorted by name, each
    checked by :func:`refuse_evaluation`."""
    files: list[Path] = []
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.rglob("*") if q.suffix.lower() == ".bvh")
            if not found:
                raise InputError(f"{item}: no .bvh files in this folder")
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            raise InputError(f"{item}: no such file or folder")
    for f in files:
        refuse_evaluation(f)
    seen, out = set(), []
    for f in sorted(files, key=lambda q: (q.name, str(q))):
        if f.resolve() not in seen:
            seen.add(f.resolve())
            out.append(f)
    return out


def clip_poses(path: Path, fps: float = TRAIN_FPS) -> np.ndarray:
    """(F, 17, 3) canonical joints of one clip at ``fps``."""
    from ..synthetic.motion import load_motion

    return load_motion(str(path), fps=fps).joints


def fit_mixture(x: np.ndarray, k: int, *, seed: int = SEED, reg: float = REGULARISATION,
                iterations: int = EM_ITERATIONS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(weights (k,), means (k, D), covariances (k, D, D)) of a Gaussian mixture fitted to ``x`` (N, D) by EM.

    Deterministic: k-means++ seeding with ``seed``, then ``iterations`` EM steps; ``reg`` is added to
    every covariance's diagonal (the features are unit vectors, so some directions hardly vary)."""
    rng = np.random.default_rng(seed)
    n, d = x.shape
    k = max(1, min(int(k), n))
    centres = [x[int(rng.integers(n))]]
    dist = np.sum((x - centres[0]) ** 2, axis=1)
    for _ in range(1, k):
        c = x[int(rng.choice(n, p=dist / dist.sum()))] if dist.sum() > 0 else x[int(rng.integers(n))]
        centres.append(c)
        dist = np.minimum(dist, np.sum((x - c) ** 2, axis=1))
    means = np.array(centres)
    resp = np.zeros((n, k))
    resp[np.arange(n), np.argmin(((x[:, None] - means[None]) ** 2).sum(-1), axis=1)] = 1.0
    eye = np.eye(d)
    for _ in range(iterations + 1):
        nk = resp.sum(axis=0) + 1e-9
        weights = nk / n
        means = (resp.T @ x) / nk[:, None]
        cov = np.empty((k, d, d))
        for j in range(k):
            y = x - means[j]
            cov[j] = (resp[:, j, None] * y).T @ y / nk[j] + reg * eye
        log_p = component_log_densities(x, weights, means, cov)
        top = log_p.max(axis=1, keepdims=True)
        resp = np.exp(log_p - top)
        resp /= resp.sum(axis=1, keepdims=True)
    return weights, means, cov


def rate_sigma(clips: list[np.ndarray], fps: float, which: tuple[int, ...] = LIMB_BONES) -> np.ndarray:
    """RMS rate of change (per second) of every feature over consecutive frames of the clips."""
    rates = [np.diff(pose_features(j, which=which), axis=0) * fps for j in clips if len(j) > 1]
    r = np.concatenate(rates) if rates else np.zeros((1, 3 * len(which)))
    return np.sqrt(np.mean(r * r, axis=0)) + 1e-3


def train(clip_joints: list[np.ndarray], *, components: int = COMPONENTS, reg: float = REGULARISATION,
          fps: float = TRAIN_FPS, mirror: bool = True, seed: int = SEED, iterations: int = EM_ITERATIONS,
          which: tuple[int, ...] = LIMB_BONES, meta: dict | None = None) -> PosePrior:
    """A :class:`PosePrior` from clips of canonical joints (each (F, 17, 3) at ``fps``)."""
    if not clip_joints or sum(len(j) for j in clip_joints) < 2 * components:
        raise InputError("too few frames to train a pose prior")
    x = np.concatenate([pose_features(j, which=which) for j in clip_joints])
    if mirror:
        x = np.concatenate([x, np.concatenate([pose_features(mirrored_left_right(j), which=which)
                                               for j in clip_joints])])
    x = x[np.isfinite(x).all(axis=1)]
    weights, means, cov = fit_mixture(x, components, seed=seed, reg=reg, iterations=iterations)
    clips = list(clip_joints) + ([mirrored_left_right(j) for j in clip_joints] if mirror else [])
    info = {"bones": [int(b) for b in which], "components": int(weights.size), "regularisation": reg, "fps": fps,
            "mirrored_left_right": mirror,
            "seed": seed, "em_iterations": iterations, "training_frames": int(sum(len(j) for j in clip_joints))}
    info.update(meta or {})
    return PosePrior(weights, means, cov, rate_sigma(clips, fps, which), info)


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def folder_notes(inputs: list[str]) -> list[dict]:
    """Per input folder, its name and the first line of its ``SOURCE.md`` or ``README.md`` (where the clips
    came from), recorded in a trained file beside the clips."""
    out = []
    for item in inputs:
        p = Path(item)
        if not p.is_dir():
            continue
        about = ""
        for name in ("SOURCE.md", "README.md"):
            if (p / name).is_file():
                lines = [ln.strip("# ").strip() for ln in (p / name).read_text(errors="replace").splitlines()]
                about = next((ln for ln in lines if ln), "")
                break
        out.append({"folder": p.resolve().name, "about": about})
    return out


def training_clips(inputs: list[str], progress=None, sources=(), licences=()) -> tuple[list[np.ndarray], dict]:
    """(joints of every clip of ``inputs`` (:func:`collect_clips`, :func:`clip_poses`), the record of them:
    source, licence, folders, the ``sources`` given (repositories, say) and clips (name, frames, SHA-256)).

    ``licences``: the clips' licences, one per kind of clip, recorded in place of the CMU database's terms
    (:data:`LICENCE`, the default) where clips from elsewhere join them; the ``source`` is then the
    ``sources`` given (or :data:`MIXED_SOURCE`), not the CMU database alone."""
    files = collect_clips(inputs)
    if not files:
        raise InputError("no .bvh files given")
    joints, listed = [], []
    for i, f in enumerate(files):
        if progress is not None:
            progress(i / len(files), f.name)
        j = clip_poses(f)
        joints.append(j)
        listed.append({"name": f.name, "frames": int(len(j)), "sha256": sha256(f)})
    licence = "; ".join(licences) if licences else LICENCE
    # clips from elsewhere joining the CMU database's: the record names them all, not the CMU database alone
    source = SOURCE if not licences else ("; ".join(sources) if sources else MIXED_SOURCE)
    return joints, {"source": source, "licence": licence, "folders": folder_notes(inputs), "sources": list(sources),
                    "clips": listed}


def train_from_files(inputs: list[str], *, components: int = COMPONENTS, progress=None, sources=(),
                     licences=()) -> PosePrior:
    """Train on every ``.bvh`` of ``inputs`` (:func:`collect_clips`); the result records the clips."""
    joints, meta = training_clips(inputs, progress, sources, licences)
    return train(joints, components=components, meta=meta)


def add_training_arguments(parser, what: str) -> None:
    """The arguments every training command takes: the clips' folders, ``--source`` and ``--out`` (the
    ``what`` file)."""
    parser.add_argument("inputs", nargs="+", metavar="DIR", help="folders (or files) of .bvh training clips")
    parser.add_argument("--source", action="append", default=[], metavar="TEXT",
                        help="where the clips came from (a repository and commit), recorded in the file; repeatable")
    parser.add_argument("--licence", action="append", default=[], metavar="TEXT",
                        help="the clips' licence, recorded in the file in place of the CMU database's terms (the "
                             "default; the file's source then names the --source texts); repeatable, one per kind "
                             "of clip")
    parser.add_argument("--out", required=True, help=f"the {what} file to write (.npz)")


def output_path(out: str, what: str) -> Path:
    """``--out`` as a path, refused (one line) unless it ends in ``.npz`` and can be written (its folder
    exists): checked before any training."""
    path = Path(out)
    if path.suffix != ".npz":
        raise InputError(f"{path}: the {what} file must end in .npz")
    return Path(check_output_file(path))


def add_arguments(parser) -> None:
    add_training_arguments(parser, "prior")
    parser.add_argument("--components", type=int, default=COMPONENTS, help="mixture components (default %(default)s)")


def run(args) -> int:
    import time

    t0 = time.perf_counter()
    out = output_path(args.out, "prior")
    prior = train_from_files(args.inputs, components=args.components, sources=args.source,
                             licences=args.licence)
    prior.save(out)
    print(f"pose prior: {len(prior.meta['clips'])} clips, {prior.meta['training_frames']} frames at "
          f"{prior.meta['fps']:g} fps, {prior.n_components} components -> {out} "
          f"({out.stat().st_size / 1024:.0f} KB, {time.perf_counter() - t0:.1f} s)")
    return 0
