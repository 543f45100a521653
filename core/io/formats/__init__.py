"""Readers for 2D joint tracks from common pose detectors, all producing :class:`core.tracks.Tracks`.

:data:`FORMATS` describes each format for front ends (the Blender file
browser filter, which settings to ask for); :func:`read_any` reads a path in
any of them, guessing the format when it is not named.  Each format lives in
its own module; docs/formats.md documents the shapes, the joint mapping and
the derived joints.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass

from ...errors import InputError
from ...tracks import Tracks
from ._canonical import check_fps, check_image_size
from .coco import read_coco
from .detect import detect_format
from .dlc import read_dlc
from .generic_csv import read_generic_csv, write_generic_csv
from .mediapipe_csv import read_mediapipe_csv
from .mediapipe_json import read_mediapipe_json
from .native import read_native
from .openpose import read_openpose

__all__ = ["FORMATS", "FormatInfo", "detect_format_of", "read_any", "write_generic_csv"]


@dataclass(frozen=True)
class FormatInfo:
    """What a front end needs to know about one format.

    ``extensions`` are lower-case with the dot (``(".json",)``); for a
    Blender file browser use ``";".join("*" + e for e in extensions)``.
    ``is_folder``: the path is a folder (pick a directory, not a file).
    ``needs_fps`` / ``needs_image_size``: files of this format may lack the
    value, so the front end should offer the setting (read_any raises an
    :class:`InputError` naming the argument when it is needed and missing).
    """

    label: str
    extensions: tuple[str, ...]
    is_folder: bool
    needs_fps: bool
    needs_image_size: bool
    description: str
    reader: Callable[..., Tracks]


FORMATS: dict[str, FormatInfo] = {
    "native": FormatInfo("MonoSkel tracks JSON", (".json",), False, False, False,
                         "The project's skeleton-tracks JSON: 17 canonical joints, fps and image size included",
                         read_native),
    "openpose": FormatInfo("OpenPose JSON folder", (".json",), True, True, True,
                           "Folder of OpenPose per-frame *_keypoints.json (BODY_25 or COCO-18)", read_openpose),
    "coco": FormatInfo("COCO keypoints JSON", (".json",), False, True, True,
                       "COCO-17 keypoints: detector results list or full {images, annotations} file", read_coco),
    "mediapipe_csv": FormatInfo("MediaPipe Pose CSV", (".csv",), False, True, True,
                                "MediaPipe Pose 33 landmarks, normalised coordinates, one row per frame or "
                                "per landmark", read_mediapipe_csv),
    "mediapipe_json": FormatInfo("MediaPipe Pose JSON", (".json",), False, True, True,
                                 "MediaPipe Pose 33 landmarks per frame, normalised coordinates",
                                 read_mediapipe_json),
    "dlc": FormatInfo("DeepLabCut CSV", (".csv",), False, True, True,
                      "DeepLabCut CSV (scorer/bodyparts/coords header, x, y, likelihood per body part)", read_dlc),
    "generic_csv": FormatInfo("Generic CSV", (".csv",), False, True, True,
                              "frame,joint,x,y[,confidence] with canonical joint names", read_generic_csv),
}


def detect_format_of(path: str | os.PathLike) -> str:
    """The :data:`FORMATS` key ``read_any`` would use for ``path``."""
    return detect_format(os.fspath(path), sorted(FORMATS))


def read_any(path, *, format=None, fps=None, image_size=None, min_confidence=0.0) -> Tracks:
    """Read 2D tracks from ``path`` in ``format`` (a :data:`FORMATS` key; guessed when None).

    ``fps`` and ``image_size`` ((width, height) pixels), when given, replace
    what the file says; formats that do not store them need them.  Joints
    with confidence below ``min_confidence`` become missing.  Every problem
    with the input raises :class:`InputError` with a one-line message naming
    the file (and frame or line) and what is wrong.
    """
    try:
        source = os.fspath(path)
    except TypeError:
        raise InputError(f"path must be a file or folder path, got {path!r}") from None
    fps = check_fps(fps, source)
    image_size = check_image_size(image_size, source)
    try:
        threshold = None if isinstance(min_confidence, bool) else float(min_confidence)
    except (TypeError, ValueError, OverflowError):
        threshold = None
    if threshold is None or not math.isfinite(threshold) or not 0 <= threshold <= 1:
        raise InputError(f"{source}: min_confidence must be a number in 0..1, got {min_confidence!r}")
    if format is None:
        format = detect_format_of(source)
    elif not isinstance(format, str) or format not in FORMATS:
        raise InputError(f"{source}: unknown format {format!r}; choose one of {sorted(FORMATS)}")
    info = FORMATS[format]
    if not os.path.exists(source):
        raise InputError(f"{source}: no such {'folder' if info.is_folder else 'file'}")
    if info.is_folder and not os.path.isdir(source):
        raise InputError(f"{source}: {info.label} expects a folder, not a file")
    if not info.is_folder and os.path.isdir(source):
        raise InputError(f"{source}: {info.label} expects a file, not a folder")
    try:
        tracks = info.reader(source, fps=fps, image_size=image_size)
    except RecursionError:
        raise InputError(f"{source}: input nested too deeply") from None
    if threshold > 0:
        tracks = tracks.with_threshold(threshold)
        if not tracks.present.any():
            raise InputError(f"{source}: no joint reaches min_confidence={min_confidence}")
    tracks.meta.setdefault("format", format)
    return tracks
