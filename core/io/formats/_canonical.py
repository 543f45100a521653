"""From a format's own keypoints to the 17 canonical joints, and the clip settings.

Readers translate their keypoints into a small shared vocabulary: the 17
canonical names plus the face points ``nose``, ``l_eye``, ``r_eye``,
``l_ear``, ``r_ear``.  :func:`canonical_tracks` copies the canonical names a
format has and derives the ones it lacks from :data:`DERIVED` (in order, so a
rule may use an earlier derived joint).  A derived joint is missing in a
frame whenever any input is missing there, and its confidence is the minimum
of its inputs' confidences: a derived point is never more certain than the
least certain point it is built from.

The rules (documented in docs/formats.md, "Derived joints"):

* ``pelvis`` = midpoint of the hips;
* ``thorax`` = midpoint of the shoulders;
* ``spine``  = midpoint of pelvis and thorax;
* ``neck``   = midpoint of thorax and the ears' midpoint;
* ``head``   = the ears' midpoint pushed away from the neck by the same
  distance again: ``ears + (ears - neck)``, i.e. ``1.5 ears - 0.5 thorax``.
  This approximates the top of the head; the ears sit roughly at the skull's
  centre, and no 2D keypoint set has the head top itself.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError, MissingSettingError
from ...skeleton import JOINT_INDEX, JOINTS, N_JOINTS
from ...tracks import Tracks

FACE_POINTS: tuple[str, ...] = ("nose", "l_eye", "r_eye", "l_ear", "r_ear")
#: Every keypoint name a reader may hand to :func:`canonical_tracks`.
VOCABULARY: tuple[str, ...] = JOINTS + FACE_POINTS

#: canonical joint -> ((input name, weight), ...); applied in this order when the joint is absent.
DERIVED: dict[str, tuple[tuple[str, float], ...]] = {
    "pelvis": (("l_hip", 0.5), ("r_hip", 0.5)),
    "thorax": (("l_shoulder", 0.5), ("r_shoulder", 0.5)),
    "spine": (("pelvis", 0.5), ("thorax", 0.5)),
    "neck": (("thorax", 0.5), ("l_ear", 0.25), ("r_ear", 0.25)),
    "head": (("l_ear", 0.75), ("r_ear", 0.75), ("thorax", -0.5)),
}


def canonical_tracks(xy: np.ndarray, conf: np.ndarray, names: list[str] | tuple[str, ...], *, fps: float,
                     image_size: tuple[float, float], source: str, meta: dict | None = None) -> Tracks:
    """Tracks of the 17 canonical joints from keypoints ``names`` (a subset of :data:`VOCABULARY`).

    ``xy`` is (F, K, 2) pixels with NaN where missing, ``conf`` (F, K) with 0
    where missing; confidences above 1 are clipped to 1.
    """
    xy = np.asarray(xy, dtype=float)
    conf = np.asarray(conf, dtype=float)
    n_frames = xy.shape[0]
    if n_frames == 0:
        raise InputError(f"{source}: no frames")
    present = np.isfinite(xy).all(axis=-1) & (conf > 0)
    conf = np.where(present, np.minimum(conf, 1.0), 0.0)
    points = {name: (np.where(present[:, k, None], xy[:, k], np.nan), conf[:, k]) for k, name in enumerate(names)}
    derived = []
    for joint, recipe in DERIVED.items():
        if joint in points or not all(name in points for name, _ in recipe):
            continue
        inputs = [points[name] for name, _ in recipe]
        ok = np.all([c > 0 for _, c in inputs], axis=0)
        pos = sum(w * p for (_, w), (p, _) in zip(recipe, inputs, strict=True))
        c = np.min([c for _, c in inputs], axis=0)
        points[joint] = (np.where(ok[:, None], pos, np.nan), np.where(ok, c, 0.0))
        derived.append(joint)
    out_xy = np.full((n_frames, N_JOINTS, 2), np.nan)
    out_conf = np.zeros((n_frames, N_JOINTS))
    for joint in JOINTS:
        if joint in points:
            out_xy[:, JOINT_INDEX[joint]], out_conf[:, JOINT_INDEX[joint]] = points[joint]
    if not (out_conf > 0).any():
        raise InputError(f"{source}: no joint is present in any of the {n_frames} frames")
    info = dict(meta or {})
    info["derived_joints"] = derived
    info["unavailable_joints"] = [j for j in JOINTS if j not in points]
    return Tracks(out_xy, out_conf, fps, image_size, source, info)


def check_fps(fps, source: str = "") -> float | None:
    """Validate an ``fps`` argument (None passes through)."""
    if fps is None:
        return None
    value = None if isinstance(fps, bool) else _number(fps)
    if value is None or value <= 0:
        raise InputError(f"{source + ': ' if source else ''}fps must be a positive number, got {fps!r}")
    return value


def check_image_size(image_size, source: str = "") -> tuple[float, float] | None:
    """Validate an ``image_size`` argument ``(width, height)`` in pixels (None passes through)."""
    if image_size is None:
        return None
    try:
        w, h = image_size
    except (TypeError, ValueError):
        w = h = None
    values = [None if isinstance(v, bool) else _number(v) for v in (w, h)]
    if any(v is None or v <= 0 for v in values):
        raise InputError(f"{source + ': ' if source else ''}image_size must be (width, height) in pixels, "
                         f"got {image_size!r}")
    return values[0], values[1]


def choose_fps(arg: float | None, from_file: float | None, label: str, source: str) -> float:
    """The argument when given, else the file's value, else an error saying which argument is needed."""
    if arg is not None:
        return arg
    if from_file is not None:
        return from_file
    raise MissingSettingError(f"{source}: {label} has no frame rate; pass fps=...", "fps")


def choose_image_size(arg, from_file, label: str, source: str) -> tuple[float, float]:
    """Like :func:`choose_fps` for the image size."""
    if arg is not None:
        return arg
    if from_file is not None:
        return from_file
    raise MissingSettingError(f"{source}: {label} has no image size; pass image_size=(w, h)", "image_size")


def _number(value) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError, OverflowError):
        return None
    return out if math.isfinite(out) else None
