"""Per-frame diagnostics of an estimate as animated custom properties.

Animated custom properties show up as curves in the Graph Editor and as
numbers in the Object properties, so an animator can scrub to a bad frame and
see why it is bad (the virtual scale jumped, the stance foot switched, the
reprojection error spiked) without leaving Blender.
"""

from __future__ import annotations

import numpy as np

from . import compat

#: custom property name -> (description, interpolation)
PROPERTIES: dict[str, tuple[str, str]] = {
    "monoskel_virtual_scale": ("Peng & Li's virtual scale s' = Z0 / Zi of the pelvis", 'LINEAR'),
    "monoskel_stance": ("Foot on the ground: 0 none or unclear, 1 left, 2 right", 'CONSTANT'),
    "monoskel_reprojection_px": ("Mean reprojection error of this frame in pixels", 'LINEAR'),
    "monoskel_camera_moving": ("1 while the camera is estimated to move", 'CONSTANT'),
}
STANCE_CODES = {None: 0, "l": 1, "r": 2}


def diagnostic_series(est) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """property name -> (frame indices, values) for the frames that have a value."""
    n = len(est.frames)
    all_idx = np.arange(n)
    scale = np.array([fr.scale for fr in est.frames], dtype=float)
    stance = np.array([STANCE_CODES.get(fr.stance, 0) for fr in est.frames], dtype=float)
    moving = np.array([1.0 if fr.camera_moving else 0.0 for fr in est.frames])
    rep_idx = np.array([i for i, fr in enumerate(est.frames) if fr.reprojection_px is not None], dtype=int)
    rep = np.array([float(est.frames[i].reprojection_px) for i in rep_idx], dtype=float)
    return {
        "monoskel_virtual_scale": (all_idx, scale),
        "monoskel_stance": (all_idx, stance),
        "monoskel_reprojection_px": (rep_idx, rep),
        "monoskel_camera_moving": (all_idx, moving),
    }


def key_diagnostics(obj, est, first_frame: int, created: list) -> None:
    """Create the custom properties on ``obj`` and key them per frame."""
    series = diagnostic_series(est)
    action, made = compat.ensure_action(obj, f"{obj.name}Action")
    if made:
        created.append(action)
    fcurves = compat.ensure_fcurves(obj)
    for prop, (idx, values) in series.items():
        if idx.size == 0:
            continue
        description, interpolation = PROPERTIES[prop]
        obj[prop] = float(values[0])
        ui = obj.id_properties_ui(prop)
        ui.update(description=description)
        if prop in ("monoskel_stance", "monoskel_camera_moving"):
            ui.update(min=0.0, max=2.0 if prop == "monoskel_stance" else 1.0)
        compat.set_keys(fcurves, f'["{prop}"]', 0, idx + first_frame, values, group="MonoSkel diagnostics",
                        interpolation=interpolation)
