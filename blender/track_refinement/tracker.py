"""Blender's own tracker (libmv least-squares matching) run on a Movie Clip from the detector's joints.

For each seed frame of :func:`core.track_refinement.seed_plan` one temporary track per seen joint is
put on the clip at the detector's position and tracked forward for one window; its markers become a
:class:`core.track_refinement.TrackedRun` and the tracks are deleted. The animator's own tracks,
their selection, the scene's frame range and the borrowed editor are left as they were, also when
something fails. The clip operators need a Movie Clip Editor: an open one is used, else the largest
area of the window is turned into one for the run and turned back.
"""

from __future__ import annotations

import bpy
import numpy as np

from ...core.errors import InputError
from ...core.skeleton import JOINTS
from ...core.track_refinement import TrackedRun
from ...core.track_refinement.refine import RESEED_SHARE, carried_seeds, figure_height
from ..clip_editor import clip_editor, delete_tracks_named, kept_clip_state
from ..movie_clip import _marker_points, _tracks_collection, clip_size

#: Names of the temporary tracks (never a joint's name, so a leftover is not read as a joint).
TEMP_PREFIX = "MonoSkel refine "

#: Motion models offered (Blender's names): a joint's patch shifts, turns and changes scale.
MOTION_MODELS = ("Loc", "LocScale", "LocRot", "LocRotScale", "Affine", "Perspective")


def sizes_for(tracks, clip_scale: float) -> tuple[int, int]:
    """Pattern and search sizes in clip pixels: the pattern about 6 % of the figure's image height
    (a joint and a little of its limbs), the search wide enough for three times the detector's
    typical fast step between frames."""
    xy = tracks.xy * clip_scale
    figure = figure_height(tracks) * clip_scale
    pattern = int(np.clip(round(0.06 * figure), 11, 61)) | 1
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=-1)
    fast = float(np.nanpercentile(steps, 90)) if np.isfinite(steps).any() else 10.0
    search = int(np.clip(pattern + 2 * (3.0 * fast + 8.0), pattern + 16, 401)) | 1
    return pattern, search


def track_runs(context, clip, tracks, plan, window: int, *, first_clip_frame: int = 1, motion_model: str = "Loc",
               progress=None) -> dict[int, list[TrackedRun]]:
    """Track the seeds of ``plan`` (core ``seed_plan``) on ``clip`` for ``window`` frames each.

    ``tracks`` frame ``i`` is the clip's frame ``first_clip_frame + i``; its pixels may be at another
    resolution than the clip's (scaled). Seeds: :func:`core.track_refinement.refine.carried_seeds`.
    ``progress(done, total)`` is called after each seed frame.
    Returns joint index -> runs, in the tracks' pixels.
    """
    if motion_model not in MOTION_MODELS:
        raise InputError(f"unknown motion model '{motion_model}' (one of {', '.join(MOTION_MODELS)})")
    width, height = clip_size(clip)
    scale = width / tracks.image_size[0]
    if abs(height / tracks.image_size[1] - scale) > 0.01 * scale:
        raise InputError(f"clip '{clip.name}' is {width:g}x{height:g} px, the tracks "
                         f"{tracks.image_size[0]:g}x{tracks.image_size[1]:g}: not the same picture")
    first, last_clip = int(first_clip_frame), int(first_clip_frame) + tracks.n_frames - 1
    if first < 1 or last_clip > clip.frame_duration:
        raise InputError(f"the tracks cover clip frames {first}-{last_clip}, clip '{clip.name}' has frames "
                         f"1-{clip.frame_duration}: they are not tracks of this clip")
    scene = context.scene
    pattern, search = sizes_for(tracks, scale)
    reseed_px = RESEED_SHARE * figure_height(tracks)
    runs: dict[int, list[TrackedRun]] = {}
    collection = _tracks_collection(clip)
    with kept_clip_state(scene, clip), clip_editor(context, clip):
        settings = clip.tracking.settings
        settings.default_pattern_size, settings.default_search_size = pattern, search
        settings.default_motion_model = motion_model
        settings.default_pattern_match = "KEYFRAME"
        settings.default_frames_limit = 0
        try:
            for done, (start, seeds) in enumerate(plan):
                delete_tracks_named(clip, TEMP_PREFIX)
                for track in collection:
                    track.select = False
                clip_frame = start + first
                made = {}
                starts = carried_seeds(tracks, start, seeds, runs, reseed_px)
                for j, (x, y) in sorted(starts.items()):
                    track = collection.new(name=TEMP_PREFIX + JOINTS[j], frame=clip_frame)
                    marker = track.markers.find_frame(clip_frame, exact=True) or track.markers.insert_frame(clip_frame)
                    marker.co = (x * scale / width, 1.0 - y * scale / height)
                    track.weight = 0.0
                    track.select = True
                    made[j] = track
                scene_frame = clip_frame + int(clip.frame_start) - 1
                last = min(start + window, tracks.n_frames - 1)
                scene.frame_start = min(scene.frame_start, scene_frame)
                scene.frame_end = last + first + int(clip.frame_start) - 1
                scene.frame_set(scene_frame)
                # the tracker starts at the editor's own frame, which follows the scene's only on redraw
                context.space_data.clip_user.frame_current = scene_frame
                bpy.ops.clip.track_markers(backwards=False, sequence=True)
                for j, track in made.items():
                    xy = np.full((last - start + 1, 2), np.nan)
                    frames, pts = _marker_points(track, clip.frame_duration, width, height)
                    i = frames - (clip_frame - 1)
                    inside = (i >= 0) & (i < len(xy))
                    xy[i[inside]] = pts[inside] / scale
                    runs.setdefault(j, []).append(TrackedRun(start, xy))
                if progress is not None:
                    progress(done + 1, len(plan))
        finally:
            delete_tracks_named(clip, TEMP_PREFIX)
    return runs
