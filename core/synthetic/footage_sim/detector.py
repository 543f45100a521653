"""The errors of a real 2D pose detector, added to the generator's exact image points.

* gross outliers: a joint thrown to a random image point for 1-3 frames;
* left/right swaps of one limb pair (legs or arms) or of the whole body, for 1-8 frames;
* jitter that is larger at the extremities (wrists and ankles x2, elbows and knees x1.5);
* runs of a missing joint (0.2-1 s; or, with ``missing_as_measured``, where and as long as BlazePose
  lost joints on real footage: mostly the arms, up to 4 s);
* a confidence that falls with the error (outliers report 0.05-0.6).

Rates are shares of joint entries (outliers, missing) or of frames (swaps); each error has its own
random stream, so turning one on does not reshuffle the others.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ...skeleton import JOINT_INDEX, JOINTS, LIMB_PAIRS, N_JOINTS

#: Jitter multiplier per joint: detectors are least sure of the extremities.
JITTER_WEIGHT = np.ones(N_JOINTS)
for _name in ("l_wrist", "r_wrist", "l_ankle", "r_ankle"):
    JITTER_WEIGHT[JOINT_INDEX[_name]] = 2.0
for _name in ("l_elbow", "r_elbow", "l_knee", "r_knee"):
    JITTER_WEIGHT[JOINT_INDEX[_name]] = 1.5
#: Share of found frames in which each joint went unseen (missing or confidence under 0.5) in BlazePose's
#: tracks of real footage, and the longest such run (s): ``bench/real_footage_bench.py`` on OpenCV's
#: vtest.avi, people about 100 px tall walking across a square seen from a first floor (docs/pose_detection.md).
#: The arms hide behind the body; the torso never goes missing.  Means of left and right.
MEASURED_MISSING = {"neck": (0.006, 0.2), "head": (0.006, 0.2), "knee": (0.114, 1.9), "ankle": (0.04, 0.5),
                    "elbow": (0.318, 3.5), "wrist": (0.457, 4.2)}


def _measured_missing():
    """(17,) per-joint share of entries and (17,) longest run (s) from :data:`MEASURED_MISSING`."""
    share, longest = np.zeros(N_JOINTS), np.zeros(N_JOINTS)
    for j, name in enumerate(JOINTS):
        key = name[2:] if name[:2] in ("l_", "r_") else name
        share[j], longest[j] = MEASURED_MISSING.get(key, (0.0, 0.0))
    return share, longest


def _cut_run(visible: np.ndarray, j: int, length: int, rng) -> int:
    """Hide joint ``j`` for ``length`` frames from a random start (in place); how many seen entries that hid."""
    start = int(rng.integers(0, max(1, visible.shape[0] - length + 1)))
    hidden = int(visible[start:start + length, j].sum())
    visible[start:start + length, j] = False
    return hidden


#: (left joint, right joint) pairs a detector exchanges, per limb pair.
_PAIRS = {name: list(zip(left, right)) for name, (left, right) in LIMB_PAIRS.items()}


@dataclass(frozen=True)
class DetectorErrors:
    """Rates of each detector error (0 turns it off)."""

    outliers: float = 0.0          # share of joint entries thrown to a random point (events of 1-3 frames)
    swaps: float = 0.0             # share of frames with a left/right exchange (events of 1-8 frames)
    extremity_jitter: bool = False  # scale the noise per joint by :data:`JITTER_WEIGHT`
    missing_runs: float = 0.0      # share of joint entries missing in runs of 0.2-1 s
    confidence: bool = False       # confidence falls with the error instead of 1.0
    missing_as_measured: bool = False  # missing runs where and as long as on real footage (MEASURED_MISSING)

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def any(self) -> bool:
        return bool(self.outliers or self.swaps or self.extremity_jitter or self.missing_runs or self.confidence
                    or self.missing_as_measured)


#: The mix of the robustness benchmark (bench/robust_bench.py): 1 % outliers, 5 % of frames swapped, extremity jitter.
TYPICAL = DetectorErrors(outliers=0.01, swaps=0.05, extremity_jitter=True, missing_runs=0.01, confidence=True)


def apply_detector_errors(uv: np.ndarray, visible: np.ndarray, noise_px: float, fps: float, image_size,
                          errors: DetectorErrors, seed: int):
    """(xy, conf, log) from exact pixels ``uv`` (F, 17, 2) and ``visible`` (F, 17).

    ``log`` lists what was done (``outliers``: (frame, joint) pairs; ``swaps``: events), so tests and
    benchmarks can score the cleaning against it.
    """
    n = uv.shape[0]
    w, h = image_size
    visible = visible.copy()
    sigma = noise_px * (JITTER_WEIGHT if errors.extremity_jitter else np.ones(N_JOINTS))
    noise = np.random.default_rng([int(seed), 1]).normal(0.0, 1.0, uv.shape) * sigma[None, :, None]
    xy = uv + noise
    err = np.linalg.norm(noise, axis=-1)
    log: dict = {"outliers": [], "swaps": []}

    if errors.swaps > 0:
        rng = np.random.default_rng([int(seed), 11])
        target = errors.swaps * n
        done = 0
        while done < target:
            length = int(rng.integers(1, 9))
            start = int(rng.integers(0, max(1, n - length + 1)))
            which = rng.choice(["legs", "arms", "body"], p=[0.45, 0.3, 0.25])
            pairs = _PAIRS["legs"] + _PAIRS["arms"] if which == "body" else _PAIRS[which]
            sl = slice(start, start + length)
            for a, b in pairs:
                xy[sl, a], xy[sl, b] = xy[sl, b].copy(), xy[sl, a].copy()
                visible[sl, a], visible[sl, b] = visible[sl, b].copy(), visible[sl, a].copy()
            log["swaps"].append({"start": start, "end": start + length - 1, "limbs": str(which)})
            done += length

    outlier_mask = np.zeros((n, N_JOINTS), dtype=bool)
    if errors.outliers > 0:
        rng = np.random.default_rng([int(seed), 12])
        target = errors.outliers * visible.sum()
        while outlier_mask.sum() < target:
            j = int(rng.integers(N_JOINTS))
            length = int(rng.integers(1, 4))
            start = int(rng.integers(0, max(1, n - length + 1)))
            point = np.array([rng.uniform(0, w), rng.uniform(0, h)])
            for f in range(start, min(n, start + length)):
                xy[f, j] = point + rng.normal(0.0, 3.0, 2)     # a detector's wrong blob wobbles a little
                outlier_mask[f, j] = True
                visible[f, j] = True                             # a false detection may come from anywhere
    log["outliers"] = [[int(f), int(j)] for f, j in zip(*np.nonzero(outlier_mask))]

    if errors.missing_runs > 0:
        rng = np.random.default_rng([int(seed), 13])
        target = errors.missing_runs * visible.sum()
        removed = 0
        while removed < target:
            j = int(rng.integers(N_JOINTS))
            removed += _cut_run(visible, j, max(1, int(round(rng.uniform(0.2, 1.0) * fps))), rng)
    if errors.missing_as_measured:
        rng = np.random.default_rng([int(seed), 15])
        share, longest = _measured_missing()
        for j in np.flatnonzero(share):
            target = share[j] * visible[:, j].sum()
            removed = 0
            while removed < target:
                length = max(1, int(round(rng.uniform(0.1, max(0.1, longest[j])) * fps)))
                length = min(length, max(1, int(np.ceil(target - removed))))   # a short clip is not overshot
                removed += _cut_run(visible, j, length, rng)

    if errors.confidence:
        rng = np.random.default_rng([int(seed), 14])
        scale = max(noise_px, 0.5) * 4.0
        conf = np.clip(0.95 * np.exp(-0.5 * (err / scale) ** 2) + rng.uniform(-0.05, 0.05, err.shape), 0.05, 1.0)
        conf[outlier_mask] = rng.uniform(0.05, 0.6, int(outlier_mask.sum()))
    else:
        conf = np.ones((n, N_JOINTS))
    xy = np.where(visible[..., None], xy, np.nan)
    conf = np.where(visible, conf, 0.0)
    return xy, conf, log
