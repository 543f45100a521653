"""2D joint tracks: the in-memory type and the native ``skeleton-tracks`` JSON.

Every reader (OpenPose, COCO, MediaPipe, ...) produces a :class:`Tracks`;
every estimator consumes one.  Missing joints are NaN in ``xy`` and 0 in
``conf``; there is no other way to say "missing".

Native file shape (pixels, origin top-left, y down)::

    {"format": "skeleton-tracks", "version": 1, "fps": 30.0,
     "image_size": [720, 480],
     "joints": [17 canonical names, any order],
     "frames": [[[x, y, confidence] or null, ... one per joint], ... one per frame],
     "static": {"names": ["bg_0", ...],
                "frames": [[[x, y, confidence] or null, ... one per name], ... one per frame]},
     "landmarks_3d": {"joints": [17 canonical names, any order],
                      "frames": [[[x, y, z] or null, ... one per joint] or null, ... one per frame]}}

``static`` is optional: image points of scene features that do not move in the
world (floor marks, wall corners), tracked by the user or a tracker.  They are
what pins the camera down (:mod:`core.scene_camera`); files without them read
as before.  So are ``"source"`` (where the tracks came from, e.g. the video a
detector ran on) and ``"meta"`` (an object of plain values, e.g. the detector
and its mode); they are read back into :attr:`Tracks.meta`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError
from .io.file_io import check_header, read_json_file, write_json_atomic
from .skeleton import JOINT_INDEX, JOINTS, N_JOINTS

FORMAT_NAME = "skeleton-tracks"
FORMAT_VERSION = 1


def _blank_missing(xy: np.ndarray, conf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``xy`` NaN and ``conf`` 0 wherever either says a point is missing; copies when it changes them, so
    the caller's arrays (often another Tracks' own, shared by :meth:`Tracks.replaced`) stay as they were."""
    missing = ~np.isfinite(xy).all(axis=-1) | ~(conf > 0)
    if (missing & ~np.isnan(xy).all(axis=-1)).any():
        xy = xy.copy()
        xy[missing] = np.nan
    if (missing & (conf != 0.0)).any():
        conf = conf.copy()
        conf[missing] = 0.0
    return xy, conf


@dataclass
class StaticTracks:
    """Image tracks of static scene points: ``xy`` (F, S, 2) pixels, NaN where a point is not seen,
    ``conf`` (F, S), 0 where not seen; ``names`` one per point (unique)."""

    names: tuple
    xy: np.ndarray
    conf: np.ndarray

    def __post_init__(self) -> None:
        self.names = tuple(str(n) for n in self.names)
        self.xy = np.asarray(self.xy, dtype=float)
        s = len(self.names)
        if self.xy.ndim != 3 or self.xy.shape[1:] != (s, 2):
            raise InputError(f"static tracks must be shaped (frames, {s}, 2), got {self.xy.shape}")
        self.conf = np.asarray(self.conf, dtype=float)
        if self.conf.shape != self.xy.shape[:2]:
            raise InputError(f"static confidence must be shaped {self.xy.shape[:2]}, got {self.conf.shape}")
        dupes = sorted({n for n in self.names if self.names.count(n) > 1})
        if dupes:
            raise InputError(f"static point name(s) listed twice: {dupes}")
        joints = [n for n in self.names if n in JOINT_INDEX]
        if joints:
            raise InputError(f"static point name(s) {joints} are joint names; a static point needs its own name")
        self.xy, self.conf = _blank_missing(self.xy, self.conf)

    @property
    def n_points(self) -> int:
        return len(self.names)

    @property
    def present(self) -> np.ndarray:
        return self.conf > 0

    def without(self, names) -> StaticTracks | None:
        """A copy without the points ``names`` (None when none is left)."""
        drop = set(names)
        keep = [k for k, n in enumerate(self.names) if n not in drop]
        if not keep:
            return None
        return StaticTracks([self.names[k] for k in keep], self.xy[:, keep].copy(), self.conf[:, keep].copy())


@dataclass
class Tracks:
    """2D positions of the 17 canonical joints over a clip.

    ``xy`` is (F, 17, 2) float pixels in :data:`core.skeleton.JOINTS` order,
    NaN where a joint is missing; ``conf`` is (F, 17) in [0, 1], 0 where
    missing.  ``source`` says where the data came from (for reports).
    ``static``: tracks of static scene points over the same frames, or None.

    ``landmarks_3d``: the detector's own 3D joints, or None (every format but a
    detector's own output): (F, 17, 3) float metres in :data:`core.skeleton.JOINTS`
    order, NaN where missing (a frame without a person), in the camera's axes of
    :mod:`core.camera` (x right, y down, z forward, away from the camera) with the
    origin at the centre between the hips, not at the camera.  A detector's guess
    from one picture, frame by frame, as it answered: not cleaned with the 2D
    tracks (a left/right exchange the cleaning undoes in 2D stays here), kept as
    a cue for what the picture cannot tell (:mod:`core.pose_detection.depth_cue`).
    """

    xy: np.ndarray
    conf: np.ndarray
    fps: float
    image_size: tuple[float, float]
    source: str = ""
    meta: dict = field(default_factory=dict)
    static: StaticTracks | None = None
    landmarks_3d: np.ndarray | None = None

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
        self.xy, self.conf = _blank_missing(self.xy, self.conf)
        if self.static is not None and self.static.xy.shape[0] != self.xy.shape[0]:
            raise InputError(f"{self._where()}static tracks have {self.static.xy.shape[0]} frames, "
                             f"the joints {self.xy.shape[0]}")
        if self.landmarks_3d is not None:
            pts = np.asarray(self.landmarks_3d, dtype=float)
            if pts.shape != (self.xy.shape[0], N_JOINTS, 3):
                raise InputError(f"{self._where()}3D landmarks must be shaped ({self.xy.shape[0]}, {N_JOINTS}, 3), "
                                 f"got {pts.shape}")
            missing = ~np.isfinite(pts).all(axis=-1)
            if (missing & ~np.isnan(pts).all(axis=-1)).any():     # copied only when a point is half there
                pts = pts.copy()
                pts[missing] = np.nan
            self.landmarks_3d = pts

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
        return self.replaced(xy=self.xy.copy(), conf=conf)

    def frames_between(self, first: int, last: int) -> Tracks:
        """Frames ``first``..``last`` (0-based, inclusive) alone, static tracks too; ``meta["frame_offset"]``
        says where they start in the tracks they came from (absent while that is frame 0)."""
        if not (0 <= first <= last < self.n_frames):
            raise InputError(f"{self._where()}frames {first}-{last} are not within 0-{self.n_frames - 1}")
        sl = slice(first, last + 1)
        static = None if self.static is None else StaticTracks(self.static.names, self.static.xy[sl].copy(),
                                                                 self.static.conf[sl].copy())
        meta = dict(self.meta)
        offset = int(meta.get("frame_offset", 0)) + first
        if offset:
            meta["frame_offset"] = offset
        pts = None if self.landmarks_3d is None else self.landmarks_3d[sl].copy()
        return self.replaced(xy=self.xy[sl].copy(), conf=self.conf[sl].copy(), meta=meta, static=static,
                             landmarks_3d=pts)

    def replaced(self, **changes) -> Tracks:
        """A copy with some fields changed (the static tracks, 3D landmarks and meta carried over unless given)."""
        fields = {"xy": self.xy, "conf": self.conf, "fps": self.fps, "image_size": self.image_size,
                  "source": self.source, "meta": dict(self.meta), "static": self.static,
                  "landmarks_3d": self.landmarks_3d}
        fields.update(changes)
        return Tracks(**fields)


def tracks_to_dict(tracks: Tracks) -> dict:
    """The native JSON document for ``tracks`` (canonical joint order)."""
    frames = [_entries(tracks.xy[f], tracks.conf[f]) for f in range(tracks.n_frames)]
    doc = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "fps": tracks.fps,
        "image_size": [tracks.image_size[0], tracks.image_size[1]],
        "joints": list(JOINTS),
        "frames": frames,
    }
    if tracks.static is not None:
        st = tracks.static
        doc["static"] = {"names": list(st.names),
                         "frames": [_entries(st.xy[f], st.conf[f]) for f in range(tracks.n_frames)]}
    if tracks.landmarks_3d is not None:
        doc["landmarks_3d"] = {"joints": list(JOINTS),
                               "frames": [_points_3d(tracks.landmarks_3d[f]) for f in range(tracks.n_frames)]}
    if tracks.source:
        doc["source"] = str(tracks.source)
    meta = {k: v for k, v in tracks.meta.items() if _plain(v)}
    if meta:
        doc["meta"] = meta
    return doc


def _plain(value) -> bool:
    """A value the ``meta`` object may hold: a JSON scalar or a list of them."""
    scalar = (str, int, float, bool, type(None))
    if isinstance(value, scalar):
        return not isinstance(value, float) or math.isfinite(value)
    return isinstance(value, list) and all(isinstance(v, scalar) for v in value)


def _entries(xy: np.ndarray, conf: np.ndarray) -> list:
    """One frame's points as ``[x, y, c]`` or None (rounded as the file stores them)."""
    return [[round(float(p[0]), 4), round(float(p[1]), 4), round(float(c), 4)] if c > 0 else None
            for p, c in zip(xy, conf, strict=True)]


def _points_3d(points: np.ndarray) -> list | None:
    """One frame's 3D joints as ``[x, y, z]`` or None each (0.1 mm), or None when none is there."""
    ok = np.isfinite(points).all(axis=-1)
    if not ok.any():
        return None
    return [[round(float(v), 4) for v in p] if k else None for p, k in zip(points, ok, strict=True)]


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
    xy_in, conf_in = _parse_frames(frames, names, where, "joint")
    order = [JOINT_INDEX[name] for name in names]
    xy = np.full(xy_in.shape, np.nan)
    conf = np.zeros(conf_in.shape)
    xy[:, order], conf[:, order] = xy_in, conf_in
    static = _static_from_dict(doc.get("static"), len(frames), where) if "static" in doc else None
    landmarks_3d = _landmarks_3d_from_dict(doc["landmarks_3d"], len(frames), where) if "landmarks_3d" in doc else None
    meta = {k: v for k, v in doc.get("meta", {}).items() if _plain(v)} if isinstance(doc.get("meta"), dict) else {}
    if isinstance(doc.get("source"), str):
        meta.setdefault("source", doc["source"])
    return Tracks(xy, conf, float(fps), (float(size[0]), float(size[1])), source, meta=meta, static=static,
                  landmarks_3d=landmarks_3d)


def _parse_frames(frames: list, names: list, where: str, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``[[x, y, c] | null, ...]`` rows, one per frame, into (F, K, 2) pixels and (F, K) confidence."""
    n = len(frames)
    xy = np.full((n, len(names), 2), np.nan)
    conf = np.zeros((n, len(names)))
    for f, row in enumerate(frames):
        if not isinstance(row, list) or len(row) != len(names):
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise InputError(f"{where}frame {f}: expected {len(names)} {what} entries, got {got}")
        for k, entry in enumerate(row):
            if entry is None:
                continue
            if (not isinstance(entry, list) or len(entry) != 3
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in entry)):
                raise InputError(
                    f"{where}frame {f}, {what} '{names[k]}': expected [x, y, confidence] or null, got {entry!r}")
            x, y, c = (float(v) for v in entry)
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(c)):
                raise InputError(f"{where}frame {f}, {what} '{names[k]}': non-finite value in {entry!r}")
            if c < 0:
                raise InputError(f"{where}frame {f}, {what} '{names[k]}': negative confidence {c}")
            if c > 0:
                xy[f, k] = (x, y)
                conf[f, k] = min(c, 1.0)
    return xy, conf


def _static_from_dict(block, n_frames: int, where: str) -> StaticTracks | None:
    """The optional ``static`` block (None when it lists no points)."""
    if not isinstance(block, dict):
        raise InputError(f"{where}\"static\" must be an object with \"names\" and \"frames\"")
    names = block.get("names")
    if not isinstance(names, list) or not all(isinstance(n, str) and n for n in names):
        raise InputError(f"{where}\"static\": \"names\" must be a list of non-empty names")
    frames = block.get("frames")
    if not isinstance(frames, list) or len(frames) != n_frames:
        got = len(frames) if isinstance(frames, list) else type(frames).__name__
        raise InputError(f"{where}\"static\": \"frames\" must have one entry per frame ({n_frames}), got {got}")
    if not names:
        return None
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(f"{where}\"static\": name(s) listed twice: {dupes}")
    xy, conf = _parse_frames(frames, names, f"{where}static: ", "point")
    return StaticTracks(names, xy, conf)


def _landmarks_3d_from_dict(block, n_frames: int, where: str) -> np.ndarray:
    """The optional ``landmarks_3d`` block: (F, 17, 3) metres in canonical order, NaN where null."""
    what = f"{where}\"landmarks_3d\""
    if not isinstance(block, dict):
        raise InputError(f"{what} must be an object with \"joints\" and \"frames\"")
    names = block.get("joints")
    if (not isinstance(names, list) or sorted(n for n in names if isinstance(n, str)) != sorted(JOINTS)
            or len(names) != N_JOINTS):
        raise InputError(f"{what}: \"joints\" must list the 17 canonical joint names once each")
    frames = block.get("frames")
    if not isinstance(frames, list) or len(frames) != n_frames:
        got = len(frames) if isinstance(frames, list) else type(frames).__name__
        raise InputError(f"{what}: \"frames\" must have one entry per frame ({n_frames}), got {got}")
    out = np.full((n_frames, N_JOINTS, 3), np.nan)
    order = [JOINT_INDEX[n] for n in names]
    for f, row in enumerate(frames):
        if row is None:
            continue
        if not isinstance(row, list) or len(row) != N_JOINTS:
            raise InputError(f"{what}: frame {f}: expected {N_JOINTS} entries or null")
        for k, entry in enumerate(row):
            if entry is None:
                continue
            if (not isinstance(entry, list) or len(entry) != 3
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                               for v in entry)):
                raise InputError(f"{what}: frame {f}, joint '{names[k]}': expected [x, y, z] in metres or null, "
                                 f"got {entry!r}")
            out[f, order[k]] = entry
    return out


def read_tracks_json(path: str | os.PathLike) -> Tracks:
    """Read a native ``skeleton-tracks`` file, with one-line errors on bad input."""
    return tracks_from_dict(read_json_file(path), os.fspath(path))
