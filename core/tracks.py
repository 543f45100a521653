"""2D joint tracks: the in-memory type and the native ``skeleton-tracks`` JSON.

Every reader (OpenPose, COCO, MediaPipe, ...) produces a :class:`Tracks`;
every estimator consumes one.  Missing joints are NaN in ``xy`` and 0 in
``conf``; there is no other way to say "missing".

Native file shape (pixels, origin top-left, y down)::

    {"format": "skeleton-tracks", "version": 1, "fps": 30.0,
     "image_size": [720, 480],
     "joints": [17 canonical names, any order],
     "frames": [[[x, y, confidence] or null, ... one per joint], ... one per frame]}
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError
from .file_io import check_header, read_json_file, write_json_atomic
from .skeleton import JOINT_INDEX, JOINTS, N_JOINTS

FORMAT_NAME = "skeleton-tracks"
FORMAT_VERSION = 1


@dataclass
class Tracks:
    """2D positions of the 17 canonical joints over a clip.

    ``xy`` is (F, 17, 2) float pixels in :data:`core.skeleton.JOINTS` order,
    NaN where a joint is missing; ``conf`` is (F, 17) in [0, 1], 0 where
    missing.  ``source`` says where the data came from (for reports).
    """

    xy: np.ndarray
    conf: np.ndarray
    fps: float
    image_size: tuple[float, float]
    source: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.xy = np.asarray(self.xy, dtype=float)
        if self.xy.ndim != 3 or self.xy.shape[1:] != (N_JOINTS, 2):
            raise InputError(f"{self._where()}tracks must be shaped (frames, 17, 2), got {self.xy.shape}")
        self.conf = np.asarray(self.conf, dtype=float)
        if self.conf.shape != self.xy.shape[:2]:
            raise InputError(f"{self._where()}confidence must be shaped {self.xy.shape[:2]}, got {self.conf.shape}")
        if not (isinstance(self.fps, (int, float)) and math.isfinite(self.fps) and self.fps > 0):
            raise InputError(f"{self._where()}fps must be a positive number, got {self.fps!r}")
        self.fps = float(self.fps)
        w, h = (float(v) for v in self.image_size)
        if not (math.isfinite(w) and math.isfinite(h) and w > 0 and h > 0):
            raise InputError(f"{self._where()}image size must be two positive numbers, got {self.image_size!r}")
        self.image_size = (w, h)
        missing = ~np.isfinite(self.xy).all(axis=-1) | ~(self.conf > 0)
        self.xy[missing] = np.nan
        self.conf[missing] = 0.0

    def _where(self) -> str:
        return f"{self.source}: " if self.source else ""

    @property
    def n_frames(self) -> int:
        return int(self.xy.shape[0])

    @property
    def present(self) -> np.ndarray:
        """(F, 17) bool: joint observed in frame."""
        return self.conf > 0

    def missing_fraction(self) -> float:
        return float(1.0 - self.present.mean()) if self.n_frames else 1.0

    def with_threshold(self, min_confidence: float) -> Tracks:
        """Copy with joints below ``min_confidence`` marked missing."""
        conf = np.where(self.conf >= min_confidence, self.conf, 0.0)
        return Tracks(self.xy.copy(), conf, self.fps, self.image_size, self.source, dict(self.meta))


def tracks_to_dict(tracks: Tracks) -> dict:
    """The native JSON document for ``tracks`` (canonical joint order)."""
    frames = []
    for f in range(tracks.n_frames):
        row = []
        for j in range(N_JOINTS):
            if tracks.conf[f, j] > 0:
                x, y = tracks.xy[f, j]
                row.append([round(float(x), 4), round(float(y), 4), round(float(tracks.conf[f, j]), 4)])
            else:
                row.append(None)
        frames.append(row)
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "fps": tracks.fps,
        "image_size": [tracks.image_size[0], tracks.image_size[1]],
        "joints": list(JOINTS),
        "frames": frames,
    }


def write_tracks_json(tracks: Tracks, path: str | os.PathLike) -> None:
    """Write ``tracks`` as a native ``skeleton-tracks`` file (atomically)."""
    write_json_atomic(tracks_to_dict(tracks), path, what="tracks file")


def tracks_from_dict(doc, source: str = "") -> Tracks:
    """Validate a parsed native document and build :class:`Tracks`.

    Every problem raises :class:`InputError` naming ``source`` and, where it
    applies, the frame and joint.
    """
    try:
        return _tracks_from_dict(doc, source)
    except OverflowError:
        raise InputError(f"{source + ': ' if source else ''}a number is too large") from None


def _tracks_from_dict(doc, source: str) -> Tracks:
    where = f"{source}: " if source else ""
    check_header(doc, FORMAT_NAME, FORMAT_VERSION, where)
    fps = doc.get("fps")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not math.isfinite(fps) or fps <= 0:
        raise InputError(f"{where}\"fps\" must be a positive number, got {fps!r}")
    size = doc.get("image_size")
    if (not isinstance(size, list) or len(size) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0
                       for v in size)):
        raise InputError(f"{where}\"image_size\" must be [width, height] in pixels, got {size!r}")
    names = doc.get("joints")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise InputError(f"{where}\"joints\" must be a list of joint names")
    unknown = [n for n in names if n not in JOINT_INDEX]
    if unknown:
        raise InputError(f"{where}unknown joint name(s) {unknown}; expected the canonical names {list(JOINTS)}")
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(f"{where}joint name(s) listed twice: {dupes}")
    lacking = [n for n in JOINTS if n not in names]
    if lacking:
        raise InputError(f"{where}\"joints\" lacks {lacking}; list all 17 (use null entries for missing data)")
    frames = doc.get("frames")
    if not isinstance(frames, list) or not frames:
        raise InputError(f"{where}\"frames\" is empty or not a list")
    n = len(frames)
    xy = np.full((n, N_JOINTS, 2), np.nan)
    conf = np.zeros((n, N_JOINTS))
    order = [JOINT_INDEX[name] for name in names]
    for f, row in enumerate(frames):
        if not isinstance(row, list) or len(row) != len(names):
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise InputError(f"{where}frame {f}: expected {len(names)} joint entries, got {got}")
        for k, entry in enumerate(row):
            if entry is None:
                continue
            if (not isinstance(entry, list) or len(entry) != 3
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in entry)):
                raise InputError(
                    f"{where}frame {f}, joint '{names[k]}': expected [x, y, confidence] or null, got {entry!r}")
            x, y, c = (float(v) for v in entry)
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(c)):
                raise InputError(f"{where}frame {f}, joint '{names[k]}': non-finite value in {entry!r}")
            if c < 0:
                raise InputError(f"{where}frame {f}, joint '{names[k]}': negative confidence {c}")
            if c > 0:
                xy[f, order[k]] = (x, y)
                conf[f, order[k]] = min(c, 1.0)
    return Tracks(xy, conf, float(fps), (float(size[0]), float(size[1])), source)


def read_tracks_json(path: str | os.PathLike) -> Tracks:
    """Read a native ``skeleton-tracks`` file, with one-line errors on bad input."""
    return tracks_from_dict(read_json_file(path), os.fspath(path))
