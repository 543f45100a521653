"""Blender's own tracker (libmv least-squares matching) run on a Movie Clip from the detector's joints.

For each seed frame of :func:`core.track_refinement.seed_plan` one temporary track per seen joint is
put on the clip at the detector's position and tracked forward for one window; its markers become a
:class:`core.track_refinement.TrackedRun` and the tracks are deleted. The animator's own tracks,
their selection, the scene's frame range and the borrowed editor are left as they were, also when
something fails. The clip operators need a Movie Clip Editor: an open one is used, else the largest
area of the window is turned into one for the run and turned back.
"""

from __future__ import annotations

import contextlib

import bpy
import numpy as np

from ...core.errors import InputError
from ...core.skeleton import JOINTS
from ...core.track_refinement import TrackedRun
from ..movie_clip import _tracks_collection, clip_size

#: Names of the temporary tracks (never a joint's name, so a leftover is not read as a joint).
TEMP_PREFIX = "MonoSkel refine "

#: A detector position this share of the figure's height away from where the joint's previous run
#: reached is taken for a miss, and the run goes on from its own position instead.
RESEED_SHARE = 0.025

#: Motion models offered (Blender's names): a joint's patch shifts, turns and changes scale.
MOTION_MODELS = ("Loc", "LocScale", "LocRot", "LocRotScale", "Affine", "Perspective")


@contextlib.contextmanager
def clip_editor(context, clip):
    """A context override in which the clip operators act on ``clip``."""
    window = context.window or (context.window_manager.windows[0] if context.window_manager.windows else None)
    if window is None:
        raise InputError("Refining tracks needs a window (Blender's tracker runs in a Movie Clip Editor)")
    areas = [a for a in window.screen.areas if a.type == "CLIP_EDITOR"]
    area = areas[0] if areas else max(window.screen.areas, key=lambda a: a.width * a.height)
    old_type, old_ui_type = area.type, getattr(area, "ui_type", None)
    if area.type != "CLIP_EDITOR":
        area.type = "CLIP_EDITOR"
    space = area.spaces.active
    old_clip, old_mode = space.clip, space.mode
    try:
        space.clip = clip
        space.mode = "TRACKING"
        region = next(r for r in area.regions if r.type == "WINDOW")
        with context.temp_override(window=window, area=area, region=region, space_data=space):
            yield
    finally:
        space.clip = old_clip
        space.mode = old_mode
        if old_type != "CLIP_EDITOR":
            area.type = old_type
            if old_ui_type is not None:
                area.ui_type = old_ui_type


@contextlib.contextmanager
def _kept_state(scene, clip):
    """Scene frames, tracking defaults and the user's track selection, restored afterwards."""
    frames = (scene.frame_start, scene.frame_end, scene.frame_current)
    settings = clip.tracking.settings
    defaults = {name: getattr(settings, name) for name in
                ("default_pattern_size", "default_search_size", "default_motion_model", "default_pattern_match",
                 "default_correlation_min", "default_frames_limit")}
    selected = {t.name: bool(t.select) for t in _tracks_collection(clip)}
    try:
        yield
    finally:
        for name, value in defaults.items():
            setattr(settings, name, value)
        for track in _tracks_collection(clip):
            if track.name in selected:
                track.select = selected[track.name]
        scene.frame_start, scene.frame_end = frames[0], frames[1]
        scene.frame_set(frames[2])


def _delete_temporary(clip) -> None:
    """Delete every temporary track (only they are selected for the delete)."""
    tracks = list(_tracks_collection(clip))
    temp = [t for t in tracks if t.name.startswith(TEMP_PREFIX)]
    if not temp:
        return
    for track in tracks:
        track.select = track.name.startswith(TEMP_PREFIX)
    bpy.ops.clip.delete_track()


def figure_height(tracks) -> float:
    """The figure's median image height in the tracks' pixels (200 when no frame shows it)."""
    seen = np.isfinite(tracks.xy[..., 1]).any(axis=1)
    if not seen.any():
        return 200.0
    y = tracks.xy[seen, :, 1]
    return float(np.median(np.nanmax(y, axis=1) - np.nanmin(y, axis=1)))


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


def _seed_positions(tracks, start: int, seeds: dict, runs: dict, reseed_px: float) -> dict:
    """Where each joint's run from ``start`` begins: the detector's position, unless the joint's
    previous run reached this frame agreeing with the detector on its last two frames before it and
    the detector is missing here or further than ``reseed_px`` from that run's position (then the run's
    position, moved by its mean offset to the detector, so the runs do not drift from the detector)."""
    starts = dict(seeds)
    for j, joint_runs in runs.items():
        run = joint_runs[-1]
        k = start - run.start
        if not (1 <= k < len(run.xy)) or not np.isfinite(run.xy[k]).all() or k < 3:
            continue
        frames = run.start + np.arange(k + 1)
        diff = tracks.xy[frames, j] - run.xy[:k + 1]
        seen = np.isfinite(diff).all(axis=1)
        if seen.sum() < 3:
            continue
        offset = np.median(diff[seen], axis=0)
        recent = diff[k - 2:k]
        if not (np.isfinite(recent).all() and (np.linalg.norm(recent - offset, axis=1) <= reseed_px).all()):
            continue                       # the run may have slipped: the detector decides
        here = run.xy[k] + offset
        if j not in seeds or np.hypot(seeds[j][0] - here[0], seeds[j][1] - here[1]) > reseed_px:
            starts[j] = (float(here[0]), float(here[1]))
    return starts


def track_runs(context, clip, tracks, plan, window: int, *, first_clip_frame: int = 1, motion_model: str = "Loc",
               progress=None) -> dict[int, list[TrackedRun]]:
    """Track the seeds of ``plan`` (core ``seed_plan``) on ``clip`` for ``window`` frames each.

    ``tracks`` frame ``i`` is the clip's frame ``first_clip_frame + i``; its pixels may be at another
    resolution than the clip's (scaled). Seeds: :func:`_seed_positions`. ``progress(done, total)`` is
    called after each seed frame.
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
    with _kept_state(scene, clip), clip_editor(context, clip):
        settings = clip.tracking.settings
        settings.default_pattern_size, settings.default_search_size = pattern, search
        settings.default_motion_model = motion_model
        settings.default_pattern_match = "KEYFRAME"
        settings.default_frames_limit = 0
        try:
            for done, (start, seeds) in enumerate(plan):
                _delete_temporary(clip)
                for track in collection:
                    track.select = False
                clip_frame = start + first
                made = {}
                starts = _seed_positions(tracks, start, seeds, runs, reseed_px)
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
                    for marker in track.markers:
                        i = int(marker.frame) - clip_frame
                        if 0 <= i < len(xy) and not marker.mute:
                            u, v = float(marker.co[0]) + track.offset[0], float(marker.co[1]) + track.offset[1]
                            xy[i] = (u * width / scale, (1.0 - v) * height / scale)
                    runs.setdefault(j, []).append(TrackedRun(start, xy))
                if progress is not None:
                    progress(done + 1, len(plan))
        finally:
            _delete_temporary(clip)
    return runs
