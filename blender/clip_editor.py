"""The Movie Clip Editor borrowed for Blender's clip operators, and the state they change put back.

Blender's tracking operators (track, detect features, delete) act on the clip of a Movie Clip Editor.
Refine Tracks on Footage and Track Background both run them from the 3D Viewport's sidebar, so they
borrow an editor (an open one, else the largest area turned into one) and leave the scene's frames,
the clip's tracking defaults and the animator's track selection as they found them.
"""

from __future__ import annotations

import contextlib

import bpy

from ..core.errors import InputError
from .movie_clip import _tracks_collection


@contextlib.contextmanager
def clip_editor(context, clip):
    """A context override in which the clip operators act on ``clip``."""
    window = context.window or (context.window_manager.windows[0] if context.window_manager.windows else None)
    if window is None:
        raise InputError("Tracking on the clip needs a window (Blender's tracker runs in a Movie Clip Editor)")
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
def kept_clip_state(scene, clip):
    """Scene frames, tracking defaults and the user's track selection, restored afterwards."""
    frames = (scene.frame_start, scene.frame_end, scene.frame_current)
    settings = clip.tracking.settings
    defaults = {name: getattr(settings, name) for name in
                ("default_pattern_size", "default_search_size", "default_motion_model", "default_pattern_match",
                 "use_default_brute", "use_default_normalization",
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


def delete_tracks_named(clip, prefix: str) -> None:
    """Delete the clip's tracks whose names start with ``prefix`` (only they are selected for the delete);
    needs :func:`clip_editor`."""
    tracks = list(_tracks_collection(clip))
    if not any(t.name.startswith(prefix) for t in tracks):
        return
    for track in tracks:
        track.select = track.name.startswith(prefix)
    bpy.ops.clip.delete_track()
