"""Residual lines through the camera: each joint's reprojection joined to its track, coloured by distance.

The tracks view (``blender/build_tracks_view.py``) puts the 2D tracks on a plane in front of the
active take's camera.  This overlay adds, on the same plane and for the current frame, a dot where the
solved joint lands through the solved camera and a line from it to the track, green when close,
yellow at the poor-fit limit, red at twice it (:func:`core.review.residuals.residual_colours`).

It is drawn with the ``gpu`` module from a viewport draw handler, which is installed only when Blender
has a window (never in background runs, where ``gpu`` cannot draw).  Everything the handler draws
comes from :func:`residual_geometry`, plain data that headless tests check against the camera.
"""

from __future__ import annotations

import bpy
import numpy as np

from ...core.review.problems import poor_fit_limit_px
from ...core.review.residuals import DEFAULT_LIMIT_PX, reprojected_pixels, residual_colours, residual_lines
from ..build_tracks_view import IMAGE_PLANE_DISTANCE_M, image_plane_points
from . import takes as _takes

#: Slightly nearer than the tracks so the lines draw over the markers.
PLANE_DISTANCE_M = 0.999 * IMAGE_PLANE_DISTANCE_M
_cache: dict = {}
_handle = None


def _clip_data(scene, take):
    """Per-frame arrays of the active take (cached until it is rebuilt or the tracks change)."""
    settings = scene.monoskel
    key = (take.build_id, settings.tracks_source, settings.tracks_frames)
    data = _cache.get(scene.name)
    if data is not None and data["key"] == key:
        return data
    from ..scene_data import load_tracks

    est = _takes.load_take_estimate(take)
    tracks = load_tracks(scene)
    if est is None or tracks is None or tracks.n_frames != len(est.frames):
        data = {"key": key, "ok": False}
    else:
        track_xy, reproj, residual, drawn = residual_lines(tracks.xy, tracks.present,
                                                           reprojected_pixels(est, tracks.image_size))
        limit = poor_fit_limit_px(est) or DEFAULT_LIMIT_PX
        focal = np.array([fr.focal_mm for fr in est.frames], dtype=float)
        data = {"key": key, "ok": True, "track": track_xy, "reproj": reproj, "residual": residual, "drawn": drawn,
                "focal": focal, "image_size": tracks.image_size, "limit": float(limit)}
    _cache[scene.name] = data
    return data


def residual_geometry(scene, frame: int | None = None) -> dict | None:
    """World-space geometry of the current (or given scene) frame for the active take, or None.

    {"track": (n, 3), "reprojection": (n, 3), "colour": (n, 4), "residual_px": (n,), "joints": (n,) int}
    for the n joints that are both tracked and solved on that frame.
    """
    settings = scene.monoskel
    take = _takes.active_take(settings)
    if take is None or take.camera is None or take.estimate is None:
        return None
    data = _clip_data(scene, take)
    if not data["ok"]:
        return None
    i = (scene.frame_current if frame is None else frame) - settings.tracks_first_frame
    if not 0 <= i < data["track"].shape[0]:
        return None
    joints = np.flatnonzero(data["drawn"][i])
    if joints.size == 0:
        return None
    focal = np.full(2, data["focal"][i])
    pair = np.stack([data["track"][i, joints], data["reproj"][i, joints]])          # (2, n, 2)
    local = image_plane_points(pair, focal, data["image_size"], PLANE_DISTANCE_M)   # (2, n, 3) camera axes
    m = np.array(take.camera.matrix_world)
    world = local @ m[:3, :3].T + m[:3, 3]
    residual = data["residual"][i, joints]
    return {"track": world[0], "reprojection": world[1], "colour": residual_colours(residual, data["limit"]),
            "residual_px": residual, "joints": joints}


# ----------------------------------------------------------------------------- drawing (needs a window)

def _draw() -> None:
    context = bpy.context
    scene = getattr(context, "scene", None)
    settings = getattr(scene, "monoskel", None)
    if settings is None or not settings.show_residuals:
        return
    try:
        take = _takes.active_take(settings)
        if take is None or take.camera is None or not take.camera.visible_get():
            return
        geo = residual_geometry(scene)
        if geo is None:
            return
        import gpu
        from gpu_extras.batch import batch_for_shader

        n = geo["track"].shape[0]
        pos = np.empty((2 * n, 3), dtype=np.float32)
        pos[0::2], pos[1::2] = geo["track"], geo["reprojection"]
        colour = np.repeat(geo["colour"].astype(np.float32), 2, axis=0)
        line = gpu.shader.from_builtin("POLYLINE_SMOOTH_COLOR")
        line.uniform_float("viewportSize", gpu.state.viewport_get()[2:])
        line.uniform_float("lineWidth", 2.0)
        gpu.state.blend_set("ALPHA")
        gpu.state.depth_test_set("NONE")
        batch_for_shader(line, "LINES", {"pos": pos.tolist(), "color": colour.tolist()}).draw(line)
        dots = gpu.shader.from_builtin("FLAT_COLOR")
        gpu.state.point_size_set(5.0)
        batch_for_shader(dots, "POINTS", {"pos": geo["reprojection"].astype(np.float32).tolist(),
                                          "color": geo["colour"].astype(np.float32).tolist()}).draw(dots)
        gpu.state.blend_set("NONE")
    except ReferenceError:
        return      # a take being rebuilt or removed mid-redraw: draw nothing this time
    except Exception as exc:  # noqa: BLE001 - a draw callback must not raise into Blender's redraw
        _say_once(exc)


_said: set = set()


def _say_once(exc: BaseException) -> None:
    """A drawing failure is reported once per kind on the console, not hidden and not repeated per redraw."""
    key = (type(exc).__name__, str(exc))
    if key not in _said:
        _said.add(key)
        print(f"MonoSkel: residual lines not drawn: {type(exc).__name__}: {exc}")


def register() -> None:
    """Install the draw handler when Blender can draw (not in background runs)."""
    global _handle
    if _handle is None and not bpy.app.background:
        _handle = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")


def unregister() -> None:
    global _handle
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    _cache.clear()
