"""Which shots a folder holds: every tracks file and video in it, one shot each, in name order.

A shot is named after its file (``walk.json`` -> ``walk``); two files with the same stem keep their
extension in the name (``walk_json``, ``walk_csv``), so each shot has its own output folder.  A tracks file
and a video with the same stem are one shot: the tracks are built and the video is their footage
(``--footage``, used by ``--track-background``).  A sub-folder holding OpenPose ``*_keypoints.json`` frames is
one tracks shot; loose ``*_keypoints.json`` frames, hidden files and anything else are left alone.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import InputError

TRACKS_EXTENSIONS = (".json", ".csv")
#: What ``batch.py --video`` decodes (Blender's ffmpeg); the same list as core.pose_detection.frames.VIDEOS.
VIDEO_EXTENSIONS = (".mp4", ".mov", ".m4v", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".mts", ".gif")
TRACKS, VIDEO = "tracks", "video"


@dataclass(frozen=True)
class Shot:
    """One shot: ``path`` is a tracks file or OpenPose folder (``kind`` TRACKS) or a video (VIDEO)."""

    name: str
    path: str
    kind: str
    footage: str | None = None      # the video beside a tracks file of the same stem

    def input_files(self) -> list[str]:
        """The files whose change makes the shot's outputs stale."""
        files = [self.path] if os.path.isfile(self.path) else sorted(
            os.path.join(self.path, n) for n in os.listdir(self.path) if n.lower().endswith(".json"))
        return files + ([self.footage] if self.footage else [])


def _is_openpose_folder(path: str) -> bool:
    try:
        return any(n.lower().endswith("_keypoints.json") for n in os.listdir(path))
    except OSError:
        return False


def discover_shots(folder: str) -> list[Shot]:
    """The shots in ``folder`` (not its sub-folders, except OpenPose ones), sorted by name."""
    if not os.path.isdir(folder):
        raise InputError(f"{folder}: no such folder (--folder)")
    folder = os.path.abspath(folder)
    tracks, videos = {}, {}
    for entry in sorted(os.listdir(folder)):
        path = os.path.join(folder, entry)
        stem, ext = os.path.splitext(entry)
        if entry.startswith("."):
            continue
        if os.path.isdir(path):
            if _is_openpose_folder(path):
                tracks.setdefault(entry, []).append((path, "folder"))
        elif ext.lower() in TRACKS_EXTENSIONS and not entry.lower().endswith("_keypoints.json"):
            tracks.setdefault(stem, []).append((path, ext.lower()[1:]))
        elif ext.lower() in VIDEO_EXTENSIONS:
            videos.setdefault(stem, []).append((path, ext.lower()[1:]))
    shots = []
    for stem, found in tracks.items():
        footage = videos.pop(stem)[0][0] if stem in videos and len(videos[stem]) == 1 else None
        shots += [Shot(stem if len(found) == 1 else f"{stem}_{tag}", path, TRACKS, footage) for path, tag in found]
    for stem, found in videos.items():
        taken = stem in tracks
        shots += [Shot(f"{stem}_{tag}" if (len(found) > 1 or taken) else stem, path, VIDEO) for path, tag in found]
    shots.sort(key=lambda s: s.name)
    names = [s.name for s in shots]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:   # e.g. walk.json, walk.csv and a file named walk_json.csv
        raise InputError(f"{folder}: several inputs would be named {', '.join(clash)}; rename one of them")
    return shots


def find_shot(folder: str, name: str) -> Shot:
    """The shot ``name`` of ``folder`` (``--shot``), with a one-line error listing the names when absent."""
    shots = discover_shots(folder)
    for shot in shots:
        if shot.name == name:
            return shot
    listed = ", ".join(s.name for s in shots[:20]) + (" ..." if len(shots) > 20 else "")
    raise InputError(f"{folder} has no shot {name!r} (shots: {listed or 'none'})")
