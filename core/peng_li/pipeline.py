"""Peng & Li (2006) end to end: tracks -> proportions, camera and virtual scale.

Steps, one module each: rectify (3.1) -> segmentation (3.2) -> stance and camera
motion per moving spell (3.3) -> undo the camera (3.4) -> stance in still spells
-> virtual scale (4.1) -> lower bounds and lengths (4.2).  All geometry is in
film millimetres (:mod:`core.camera`), so thresholds do not depend on the image
resolution.  The method needs the initial focal length: the user's hint, else the
paper's default of 50 mm.  Beyond the paper, and off in its own setting: the planted
ankle's creep taken out before a rotating camera is tracked (:mod:`.foot_drift`).
"""

from __future__ import annotations

import numpy as np

from ..camera import DEFAULT_FOCAL_MM, pixels_to_film, rotation_matrix, rotvec_deg
from ..errors import Cancelled, InputError
from ..result import Estimate, FrameEstimate
from ..skeleton import FEET, class_lengths_for_height, class_lengths_from_segments, proportions, proportions_dict
from ..tracks import Tracks
from .camera_motion import SpellCamera, estimate_spell_models, size_roughness
from .foot_drift import stance_ankle_drift
from .lower_bounds import frame_lower_bounds
from .params import PAPER, PaperParams
from .rectify import rectify
from .segmentation import foot_steps, segment
from .stance import fill_unknown, stance_dp
from .undo_camera import camera_rotations, undo_camera
from .virtual_scale import virtual_scale

METHOD_NAME = "paper"
#: Film millimetres per pixel of a 720-pixel-wide image: thresholds are given in those pixels.
_MM_PER_PX_720 = 36.0 / 720.0
MIN_FRAMES = 10


def _check_input(tracks: Tracks) -> None:
    where = f"{tracks.source}: " if tracks.source else ""
    n = tracks.n_frames
    need = max(MIN_FRAMES, int(round(tracks.fps)))
    if n < need:
        raise InputError(f"{where}too few frames ({n}); the paper's method needs at least {need} (1 s)")
    present = tracks.present
    if not present.any():
        raise InputError(f"{where}all joints are missing in every frame")
    feet = present[:, [FEET["l"], FEET["r"]]]
    if not feet.any():
        raise InputError(f"{where}no foot (ankle) is visible in any frame; the stance foot is needed")
    if present[:, 0].sum() < 2:
        raise InputError(f"{where}the pelvis is visible in fewer than 2 frames; it is the root of the skeleton")


def measured_noise_px(raw: np.ndarray, smoothed: np.ndarray) -> float:
    """2D noise level (standard deviation, pixels of a 720-wide image) from raw vs smoothed film points.

    The median absolute residual ignores the few fast joints the filter cannot follow;
    1.4826 turns it into a standard deviation, and ~0.94 (measured on synthetic noise) is the share a
    short smoothing window leaves in the residual.
    """
    r = (raw - smoothed).ravel()
    r = r[np.isfinite(r)]
    if r.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(r)) / 0.94 / _MM_PER_PX_720)


def stillness_stance(feet: np.ndarray, fps: float, params: PaperParams) -> np.ndarray:
    """Stance per frame (0/1) on still-camera data: the foot whose projection is stiller."""
    steps = foot_steps(feet)
    steps[0] = steps[1] if steps.shape[0] > 1 else 0.0
    return stance_dp(fill_unknown(steps), None, params.window_frames(params.min_stance_s, fps))


def body_stance_cue(pts: np.ndarray) -> np.ndarray:
    """(n, 2) squared image speed of each ankle relative to the pelvis, film mm per frame (not the paper).

    A directional rotating camera shifts a distant figure's joints alike, so the difference of two
    joints' image speeds is the figure's own motion: a planted ankle moves against the pelvis at the
    body's walking speed, a swinging one outruns it.  Unknown speeds cost the 90th percentile.
    """
    rel = pts[:, [FEET["l"], FEET["r"]]] - pts[:, None, 0]
    v = np.full(rel.shape, np.nan)
    if len(v) > 1:
        v[1:] = np.diff(rel, axis=0)
        v[0] = v[1]
    return fill_unknown(np.sum(v * v, axis=-1), default=0.0)


def choose_model(options: list[SpellCamera], pts: np.ndarray, a: int, b: int, before: tuple[float, float, float],
                 f0: float, fps: float, params: PaperParams) -> SpellCamera:
    """Pick the camera model of frames a..b: by smoothness if clear, else by enlargement/shrinking."""
    options = sorted(options, key=lambda o: o.cost)
    if len(options) == 1 or options[0].cost < params.model_cost_ratio * options[1].cost:
        return options[0]
    n = pts.shape[0]
    c = params.window_frames(params.size_context_s, fps)
    lo, hi = max(0, a - c), min(n - 1, b + c)
    scores = []
    for o in options:
        pan = np.concatenate([np.full(a - lo, before[0]), o.pan_deg, np.full(hi - b, o.pan_deg[-1])])
        tilt = np.concatenate([np.full(a - lo, before[1]), o.tilt_deg, np.full(hi - b, o.tilt_deg[-1])])
        focal = np.concatenate([np.full(a - lo, before[2]), o.focal_mm, np.full(hi - b, o.focal_mm[-1])])
        static = undo_camera(pts[lo:hi + 1], camera_rotations(pan, tilt), focal, f0)
        scores.append(size_roughness(static))
    scores = [s if np.isfinite(s) else np.inf for s in scores]
    return options[int(np.argmin(scores))]


def _scene_camera(tracks: Tracks, focal_mm, given):
    """The usable camera from the background tracks, or None (none given and none to solve, or unusable)."""
    if tracks.static is None:
        return None
    if given is None:
        from ..scene_camera import focal_arguments, solve_scene_camera

        given = solve_scene_camera(tracks, **focal_arguments(tracks, focal_mm))
    return given if given is not None and given.usable else None


#: A known camera "moves" in a frame where it turns or zooms faster than this (degrees, log focal per frame).
MOVING_DEG_PER_FRAME = 0.02
MOVING_ZOOM_PER_FRAME = 0.0005


def _moving_from_camera(rotvecs_deg: np.ndarray, focal_mm: np.ndarray) -> np.ndarray:
    """(F,) bool: the known camera turns or zooms between this frame and its neighbour."""
    n = len(focal_mm)
    moving = np.zeros(n, dtype=bool)
    if n < 2:
        return moving
    R = rotation_matrix(rotvecs_deg)
    step = np.linalg.norm(rotvec_deg(R[1:] @ np.transpose(R[:-1], (0, 2, 1))), axis=1)
    fast = (step > MOVING_DEG_PER_FRAME) | (np.abs(np.diff(np.log(focal_mm))) > MOVING_ZOOM_PER_FRAME)
    moving[1:] |= fast
    moving[:-1] |= fast
    return moving


def _spells_of(moving: np.ndarray) -> list:
    """Still / moving runs of a known camera as :class:`.segmentation` spells."""
    from .segmentation import Spell

    out, start = [], 0
    for i in range(1, len(moving) + 1):
        if i == len(moving) or moving[i] != moving[start]:
            out.append(Spell(start, i - 1, bool(moving[start])))
            start = i
    return out


def _bound_statistic(q: float):
    if q >= 1.0:
        return np.max
    return lambda v: float(np.quantile(v, q))


def _camera_from_feet(tracks: Tracks, pts, feet, f0: float, noise_px: float, params: PaperParams, step,
                      warnings: list):
    """The paper's camera (3.2-3.4): still / moving spells from the feet (the still threshold grows with the
    measured ``noise_px``), each moving spell's camera model tracked with the stance foot, then undone.
    Returns (spells, moving, stance, focal, rot, static, drift)."""
    n, fps = tracks.n_frames, tracks.fps
    step(0.15, "segmenting still / moving camera")
    threshold = (params.still_threshold_px_per_frame + params.still_threshold_per_noise * noise_px) * _MM_PER_PX_720
    spells = segment(feet, fps, threshold, params)
    moving = np.zeros(n, dtype=bool)
    for sp in spells:
        moving[sp.start:sp.end + 1] = sp.moving
    still_share = float(np.mean(~moving))
    if still_share < params.warn_still_fraction:
        warnings.append(f"camera: a still camera was found in only {still_share:.0%} of the frames; the method "
                        "needs still spells between camera moves, so the camera track follows the stance foot "
                        "over the whole clip and may drift (running or skipping feet are never still long "
                        "enough) - check it against the footage")
    step(0.3, "stance foot and camera motion")
    drift = np.zeros(2)
    if params.stance_drift_correction:
        drift = stance_ankle_drift(feet, ~moving, stillness_stance(feet, fps, params))
    pan = np.zeros(n)
    tilt = np.zeros(n)
    focal = np.full(n, f0)
    stance = np.full(n, -1)
    min_run = params.window_frames(params.min_stance_s, fps)
    last_end = -1            # last frame already given a camera state
    for k, sp in enumerate(spells):
        if not sp.moving:
            continue
        nxt = spells[k + 2].start - 1 if k + 2 < len(spells) else n - 1
        a = max(last_end + 1, sp.start - params.motion_margin_frames, 0)
        b = min(sp.end + params.motion_margin_frames, nxt, n - 1)
        if a > 0:   # hold the camera through the still frames before this range
            pan[last_end + 1:a] = pan[last_end] if last_end >= 0 else 0.0
            tilt[last_end + 1:a] = tilt[last_end] if last_end >= 0 else 0.0
            focal[last_end + 1:a] = focal[last_end] if last_end >= 0 else f0
        p0, t0, fc = (pan[a - 1], tilt[a - 1], focal[a - 1]) if a > 0 else (0.0, 0.0, f0)
        cue = None
        if params.stance_body_weight > 0:
            cue = params.stance_body_weight * body_stance_cue(pts[a:b + 1])
        options = estimate_spell_models(feet[a:b + 1], fc, p0, t0, min_run, params.motion_models, drift=drift,
                                        body_cue=cue)
        cam = choose_model(options, pts, a, b, (p0, t0, fc), f0, fps, params)
        pan[a:b + 1], tilt[a:b + 1], focal[a:b + 1] = cam.pan_deg, cam.tilt_deg, cam.focal_mm
        stance[a:b + 1] = cam.stance
        sp.kind = cam.kind
        last_end = b
        step(0.3 + 0.3 * (sp.end + 1) / n, f"camera motion: spell {sp.start}-{sp.end} is {cam.kind}")
    if last_end < n - 1 and last_end >= 0:
        pan[last_end + 1:], tilt[last_end + 1:], focal[last_end + 1:] = pan[last_end], tilt[last_end], focal[last_end]
    step(0.6, "undoing the camera motion")
    rot = camera_rotations(pan, tilt)
    static = undo_camera(pts, rot, focal, f0)
    return spells, moving, stance, focal, rot, static, drift


def estimate_paper(tracks: Tracks, *, focal_mm: float | None = None, height_m: float = 1.75, progress=None,
                   should_cancel=None, params: PaperParams | None = None, scene_camera=None) -> Estimate:
    """Run the paper's method on ``tracks`` (see the module docstring).

    With background tracks (``tracks.static``) the camera comes from them (:mod:`core.scene_camera`;
    ``scene_camera`` hands over one already solved) and is undone exactly instead of being tracked with
    the stance foot; the rest of the method is unchanged.
    """
    params = params or PAPER
    _check_input(tracks)

    def step(fraction: float, message: str) -> None:
        if should_cancel is not None and should_cancel():
            raise Cancelled()
        if progress is not None:
            progress(fraction, message)

    f0 = float(focal_mm) if focal_mm else DEFAULT_FOCAL_MM
    fps = tracks.fps
    n = tracks.n_frames
    warnings: list[str] = []

    step(0.0, "rectifying 2D data")
    film = pixels_to_film(tracks.xy, tracks.image_size)
    pts = rectify(film, fps, params)
    feet = pts[:, [FEET["l"], FEET["r"]]]
    noise_px = measured_noise_px(film, pts)

    scene = _scene_camera(tracks, focal_mm, scene_camera)
    if scene is not None:
        # the camera from the background tracks (core.scene_camera): undone exactly, no stance-foot tracking
        step(0.15, "camera from the background tracks")
        f0 = float(scene.focal_mm[0])
        rot = rotation_matrix(scene.rotvec_deg)
        focal = np.asarray(scene.focal_mm, dtype=float)
        moving = _moving_from_camera(scene.rotvec_deg, focal)
        spells = _spells_of(moving)
        stance = np.full(n, -1)
        drift = np.zeros(2)
        static = undo_camera(pts, rot, focal, f0)
    else:
        spells, moving, stance, focal, rot, static, drift = _camera_from_feet(
            tracks, pts, feet, f0, noise_px, params, step, warnings)
    step(0.65, "stance foot in still spells")
    still_stance = stillness_stance(static[:, [FEET["l"], FEET["r"]]], fps, params)
    stance = np.where(moving, stance, still_stance)
    stance = np.where(stance < 0, still_stance, stance)

    step(0.7, "virtual scale")
    scale, scale_info = virtual_scale(static, stance, params.window_frames(params.min_stance_run_for_depth_s, fps),
                                      params.extrapolate_scale)
    if "warning" in scale_info:
        warnings.append(scale_info["warning"])
    use = scale.copy()
    med = np.nanmedian(use)
    bad = ~np.isfinite(use) | (use > med * params.max_scale_ratio) | (use < med / params.max_scale_ratio)
    use[bad] = np.nan

    step(0.8, "lower bounds and segment lengths")
    _, seg_len = frame_lower_bounds(static, f0, use, statistic=_bound_statistic(params.bound_quantile))
    if not np.all(np.isfinite(seg_len)) or not np.all(seg_len > 0):
        raise InputError(f"{tracks.source or 'tracks'}: some segments are never visible with both joints; "
                         "cannot estimate every length")
    classes = class_lengths_from_segments(seg_len)
    props = proportions(classes)

    step(0.95, "writing the estimate")
    rv = rotvec_deg(rot)
    frames = [FrameEstimate(stance=("l", "r")[int(stance[i])] if stance[i] >= 0 else None,
                            camera_moving=bool(moving[i]), rotvec_deg=tuple(float(v) for v in rv[i]),
                            focal_mm=float(focal[i]), scale=float(scale[i]), joints_3d=None)
              for i in range(n)]
    diagnostics = {
        "spells": [sp.as_dict() for sp in spells],
        "focal_determined": bool(scene is not None and scene.focal_determined),
        "warnings": warnings,
        "bound_quantile": params.bound_quantile,
        "noise_px_measured": noise_px,
        "stance_drift_px_per_frame": [float(v) / _MM_PER_PX_720 for v in drift],
        "swap_frames": scale_info["swap_frames"],
        "class_lengths_m": [float(v) for v in class_lengths_for_height(props, height_m)],
    }
    if tracks.static is not None:
        diagnostics["scene_camera"] = scene.summary() if scene is not None else None
    step(1.0, "done")
    return Estimate(method=METHOD_NAME, proportions=proportions_dict(classes), focal_mm=f0, frames=frames,
                    height_m=float(height_m), diagnostics=diagnostics)
