"""Keep the sidebar's summary fields (``scene.monoskel``) in step with the scene's data.

The tracks, estimate and truth are JSON in Text datablocks (``blender/scene_data.py``);
parsing them on every redraw would make the sidebar sluggish on long clips, so each
operator that stores data also writes a few numbers here.  :func:`refresh_from_scene`
rebuilds the summary from the stored data (used after opening a file made by
``batch.py``, which does not know about the sidebar).
"""

from __future__ import annotations

import numpy as np

from ..core.skeleton import CLASSES, N_CLASSES


def set_tracks_summary(settings, tracks) -> None:
    settings.has_tracks = True
    settings.tracks_source = tracks.source or "tracks"
    settings.tracks_frames = tracks.n_frames
    settings.tracks_fps = tracks.fps
    settings.tracks_width = int(round(tracks.image_size[0]))
    settings.tracks_height = int(round(tracks.image_size[1]))
    settings.tracks_joints_present = int(tracks.present.any(axis=0).sum())
    settings.tracks_missing = tracks.missing_fraction()
    settings.tracks_static = 0 if tracks.static is None else tracks.static.n_points


def spells_text(spells) -> str:
    """'0-44 still; 45-89 pan' from a list of {"start", "end", "kind"}."""
    parts = []
    for spell in spells or ():
        try:
            parts.append(f"{int(spell['start'])}-{int(spell['end'])} {spell['kind']}")
        except (KeyError, TypeError, ValueError):
            continue
    return "; ".join(parts)


def set_estimate_summary(settings, est) -> None:
    diag = est.diagnostics or {}
    settings.has_estimate = True
    settings.est_method = est.method
    settings.est_focal_mm = float(est.focal_mm)
    settings.est_focal_determined = bool(diag.get("focal_determined", True))
    settings.est_proportions = [float(est.proportions[name]) for name in CLASSES]
    settings.est_has_motion = any(fr.joints_3d is not None for fr in est.frames)
    settings.est_spells = spells_text(diag.get("spells"))
    warnings = diag.get("warnings") or []
    settings.est_warnings = "; ".join(str(w) for w in warnings)
    settings.est_scene_camera = scene_camera_text(diag.get("scene_camera"))
    settings.est_worst_frames = worst_frames_text(est)
    settings.est_blender_solve = blender_solve_text(diag.get("blender_solve"))


def worst_frames_text(est, limit: int = 5) -> str:
    """'12:4.1,40:3.9' for the self-check's worst-fitting frames (index: mean reprojection px)."""
    worst = ((est.diagnostics or {}).get("self_check") or {}).get("worst_frames") or []
    parts = []
    for i in worst[:limit]:
        rep = est.frames[int(i)].reprojection_px if 0 <= int(i) < len(est.frames) else None
        if rep is not None:
            parts.append(f"{int(i)}:{float(rep):.1f}")
    return ",".join(parts)


def scene_camera_text(sc) -> str:
    """One line on the camera from the background tracks ("" when the tracks had none)."""
    if not sc:
        return ""
    if not sc.get("used"):
        return f"Background: {sc['points']} points, not used (see the warnings)"
    focal = "focal determined" if sc.get("focal_determined") else "focal not determined"
    return (f"Background: {sc['points_used']} of {sc['points']} points, camera turns {sc['turn_deg']:.0f} deg, "
            f"{focal}, fit {sc['residual_px']:.2f} px")


def blender_solve_text(cmp) -> str:
    """One line comparing our camera with Blender's camera solve ("" when there was none)."""
    if not cmp:
        return ""
    text = (f"Blender's camera solve: {cmp['rotation_deg_median']:.2f} deg apart (median, max "
            f"{cmp['rotation_deg_max']:.2f}) over {cmp['frames']} frames")
    if cmp.get("focal_pct") is not None:
        text += f", focal {cmp['focal_pct']:+.1f} %"
    return text


def clear_estimate_summary(settings) -> None:
    """New tracks make any earlier estimate stale: the sidebar and builders stop offering it."""
    settings.has_estimate = False
    settings.est_method = ""
    settings.est_focal_mm = 0.0
    settings.est_proportions = [0.0] * N_CLASSES
    settings.est_has_motion = False
    settings.est_spells = ""
    settings.est_warnings = ""
    settings.est_scene_camera = ""
    settings.est_worst_frames = ""
    settings.est_blender_solve = ""


def truth_proportions(truth) -> np.ndarray:
    props = truth.proportions
    if isinstance(props, dict):
        return np.array([float(props[name]) for name in CLASSES])
    return np.asarray(props, dtype=float).reshape(N_CLASSES)


def truth_focal(truth) -> float:
    """Mean true focal length (the clip may zoom); 0 when the truth does not say."""
    frames = getattr(truth, "focal_mm", None)
    if frames is None:
        frames = getattr(truth, "frames_focal_mm", None)
    if frames is None:
        return 0.0
    values = np.asarray(frames, dtype=float).ravel()
    return float(values.mean()) if values.size else 0.0


def set_truth_summary(settings, truth) -> None:
    settings.has_truth = True
    settings.truth_proportions = truth_proportions(truth).tolist()
    settings.truth_focal_mm = truth_focal(truth)


def clear_truth_summary(settings) -> None:
    settings.has_truth = False
    settings.truth_proportions = [0.0] * N_CLASSES
    settings.truth_focal_mm = 0.0


def set_views_summary(settings, views, cameras) -> None:
    """The further views on the scene: how many, where from, whether their cameras were given."""
    settings.views_count = len(views)
    settings.views_sources = ", ".join(v.source or f"view {k + 2}" for k, v in enumerate(views))
    settings.views_cameras_given = bool(views) and cameras is not None


def refresh_from_scene(scene) -> None:
    """Rebuild the whole summary from the data stored on ``scene``."""
    from ..blender import scene_data

    settings = scene.monoskel
    tracks = scene_data.load_tracks(scene)
    if tracks is None:
        settings.has_tracks = False
    else:
        set_tracks_summary(settings, tracks)
    est = scene_data.load_estimate(scene)
    if est is None:
        clear_estimate_summary(settings)
    else:
        set_estimate_summary(settings, est)
    truth = scene_data.load_truth(scene)
    if truth is None:
        clear_truth_summary(settings)
    else:
        set_truth_summary(settings, truth)
    set_views_summary(settings, *scene_data.load_views(scene))
