"""Detected joints as Movie Clip markers, so the animator sees and corrects them in the Clip Editor.

One track per canonical joint, named after it (what
:func:`blender.movie_clip.tracks_from_clip` reads back), with weight 0 so
Blender's own camera solve ignores the person.  Within the detected frames a
joint's markers are replaced: a detected joint gets a marker, a missed one
none (and a muted marker where a gap begins, so the editor does not draw the
last position on through the gap).  Markers outside those frames, and every
other track, are left alone: hand corrections elsewhere survive a re-run.
"""

from __future__ import annotations

import numpy as np

from ...core.skeleton import JOINTS
from ..movie_clip import _tracks_collection, joint_tracks


def write_joint_markers(clip, tracks, clip_frames: list[int]) -> int:
    """Write ``tracks`` (row i = clip frame ``clip_frames[i]``) as joint markers; returns markers written."""
    width, height = (float(v) for v in clip.size)
    existing = joint_tracks(clip)
    collection = _tracks_collection(clip)
    written = 0
    frames = [int(f) for f in clip_frames]
    for j, name in enumerate(JOINTS):
        present = tracks.conf[:, j] > 0
        track = existing.get(name)
        if track is None:
            if not present.any():
                continue
            first = frames[int(np.flatnonzero(present)[0])]
            track = collection.new(name=name, frame=first)
            track.weight = 0.0
        for i, frame in enumerate(frames):  # detected first, so a track never loses all its markers
            if present[i]:
                x, y = tracks.xy[i, j]
                marker = track.markers.insert_frame(frame)
                marker.co = (x / width, 1.0 - y / height)
                marker.mute = False
                written += 1
        for i, frame in enumerate(frames):
            if present[i]:
                continue
            gap_starts = i > 0 and present[i - 1]
            marker = track.markers.find_frame(frame, exact=True)
            if marker is not None and (gap_starts or len(track.markers) == 1):
                marker.mute = True
            elif marker is not None:
                track.markers.delete_frame(frame)
            elif gap_starts:
                track.markers.insert_frame(frame).mute = True
    return written
