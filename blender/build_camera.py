"""The estimated camera as a Blender camera: fixed position, keyed rotation and focal length.

Our camera axes are x right, y down, z forward; a Blender camera looks down
its local -Z with +Y up, so its local axes are ours times diag(1, -1, -1).
For frame i (``X_i = R_i X_0`` for static points), the camera's world
rotation is ``W0 @ R_i.T @ diag(1, -1, -1)`` where ``W0`` maps frame 0's
camera axes to the world.  The film is core.camera's 35 mm normalisation:
sensor fit HORIZONTAL with the sensor as wide as the image sits on that film
(36 mm for 3:2 and wider images), so Blender's lens equals our focal_mm.
Keys that repeat their neighbours are dropped, so still spells show as two
keys and moving spells as a dense run of keys in the Dope Sheet.
"""

from __future__ import annotations

import bpy
import numpy as np
from scipy.spatial.transform import Rotation

from ..core.camera import film_size_mm, rotation_matrix
from . import compat

CAM_FROM_BLENDER = np.diag([1.0, -1.0, -1.0])


def camera_world_rotations(est, w0_rot: np.ndarray) -> np.ndarray:
    """World rotation matrices (F, 3, 3) of the Blender camera object for each frame."""
    r = rotation_matrix(np.array([fr.rotvec_deg for fr in est.frames], dtype=float))
    return w0_rot @ np.swapaxes(r, -1, -2) @ CAM_FROM_BLENDER


#: Hold tolerances for dropping keys: rotation 0.002 degrees (a few hundredths of a pixel at any
#: focal length in a 720-pixel image) and lens 0.001 mm.  A solved still spell wobbles by about
#: 0.001 degrees; without a tolerance every frame would be keyed and the moving spells would not
#: stand out in the Dope Sheet.
ROTATION_HOLD_RAD = np.radians(0.002)
LENS_HOLD_MM = 0.001


def _needed_keys(values: np.ndarray, atol) -> np.ndarray:
    """Indices of rows (F, C) that are not a hold between their neighbours.

    A key is dropped only when it equals both neighbours to within ``atol`` (scalar or one per
    column), so the evaluated curve stays within ``atol`` of keying every frame.
    """
    n = values.shape[0]
    if n <= 2:
        return np.arange(n)
    same_prev = np.all(np.abs(values[1:-1] - values[:-2]) <= atol, axis=1)
    same_next = np.all(np.abs(values[1:-1] - values[2:]) <= atol, axis=1)
    keep = np.ones(n, dtype=bool)
    keep[1:-1] = ~(same_prev & same_next)
    return np.flatnonzero(keep)


def _camera_object(scene, image_size, position, name: str, created: list):
    """A camera object on core.camera's film for ``image_size``, placed at ``position``, linked to the
    scene; appends what it creates to ``created``."""
    film_w, film_h = film_size_mm(image_size)
    data = bpy.data.cameras.new(name)
    created.append(data)
    data.lens_unit = 'MILLIMETERS'
    data.sensor_fit = 'HORIZONTAL'
    data.sensor_width = film_w
    data.sensor_height = film_h
    data.clip_start = 0.05
    data.clip_end = 1000.0
    obj = bpy.data.objects.new(name, data)
    created.append(obj)
    scene.collection.objects.link(obj)
    obj.location = [float(v) for v in position]
    obj.rotation_mode = 'XYZ'
    return obj


def create_camera(scene, est, image_size, w0_rot, position, name: str, first_frame: int, created: list):
    """Camera object with keyed rotation (Euler XYZ) and lens; appends what it creates to ``created``."""
    obj = _camera_object(scene, image_size, position, name, created)
    data = obj.data

    mats = camera_world_rotations(est, w0_rot)
    euler = Rotation.from_matrix(mats).as_euler("xyz")  # extrinsic xyz == Blender's XYZ Euler
    euler = np.unwrap(euler, axis=0)
    lens = np.array([fr.focal_mm for fr in est.frames], dtype=float)
    obj.rotation_euler = [float(v) for v in euler[0]]
    data.lens = float(lens[0])
    keep = _needed_keys(np.column_stack([euler, lens]), atol=np.array([ROTATION_HOLD_RAD] * 3 + [LENS_HOLD_MM]))
    frames = keep + first_frame

    action, made = compat.ensure_action(obj, f"{name}Action")
    if made:
        created.append(action)
    fcurves = compat.ensure_fcurves(obj)
    for axis in range(3):
        compat.set_keys(fcurves, "rotation_euler", axis, frames, euler[keep, axis], group="Rotation")
    action, made = compat.ensure_action(data, f"{name}LensAction")
    if made:
        created.append(action)
    compat.set_keys(compat.ensure_fcurves(data), "lens", 0, frames, lens[keep], group="Lens")
    return obj


def view_cameras(est) -> list[tuple[str, tuple[float, float], float, np.ndarray, np.ndarray]]:
    """The further views of a multi-view estimate (``diagnostics.cameras`` beyond the first) as
    (name, image size, lens mm, rotation cam0 -> view (3, 3), centre in frame-0 camera axes (3,))."""
    from ..core.multiview.cameras import ViewCamera

    cams = (est.diagnostics or {}).get("cameras") or []
    if len(cams) < 2:
        return []
    views = [ViewCamera.from_dict(c) for c in cams]
    r0, c0 = views[0].rotation, views[0].position
    return [(v.name, v.image_size, v.focal_mm(), v.rotation @ r0.T, r0 @ (v.position - c0)) for v in views[1:]]


def create_static_camera(scene, image_size, world_rot, position, lens_mm: float, name: str, created: list):
    """A camera that does not move (one of several synchronized views): placed, no keys."""
    obj = _camera_object(scene, image_size, position, name, created)
    obj.data.lens = float(lens_mm)
    obj.rotation_euler = [float(v) for v in Rotation.from_matrix(world_rot @ CAM_FROM_BLENDER).as_euler("xyz")]
    obj["monoskel_view"] = name
    return obj


def spell_markers(spells, first_frame: int) -> list[tuple[str, int]]:
    """(name, scene frame) of a marker at the start of each camera spell ("camera: pan", ...)."""
    out = []
    for spell in spells or []:
        try:
            out.append((f"camera: {spell['kind']}", int(spell["start"]) + first_frame))
        except (KeyError, TypeError, ValueError):
            continue
    return out


def add_markers(scene, markers, created: list) -> int:
    """Add timeline markers (name, frame); one that already exists (same name, same frame) is kept, so
    rebuilding does not pile markers up.  Returns how many were added."""
    existing = {(m.name, m.frame) for m in scene.timeline_markers}
    added = 0
    for name, frame in markers:
        if (name, frame) in existing:
            continue
        created.append(scene.timeline_markers.new(name, frame=frame))
        existing.add((name, frame))
        added += 1
    return added


def mark_spells(scene, spells, first_frame: int, created: list) -> int:
    """Timeline markers at the start of each camera spell ("pan", "still", ...); returns how many were added."""
    return add_markers(scene, spell_markers(spells, first_frame), created)
