"""The 2D tracks made visible through the camera: one empty per joint on a virtual image plane.

Layout: camera > "<name>" grouping empty > 17 joint empties ("<name>.<joint>")
and one line mesh ("<name> Lines") drawing the 16 segments between them.

Each joint is an empty parented (through one grouping empty) to the camera and
keyed, per frame, at the point of a plane ``IMAGE_PLANE_DISTANCE_M`` in front
of the lens where that frame's pixel would be seen with that frame's focal
length.  Looking through the camera, the markers sit exactly on the image
positions of the tracks, so the armature can be checked against them.  A
missing joint is hidden in the viewport on that frame (a keyed
``hide_viewport``, constant interpolation), so it vanishes instead of drifting;
the marker size follows the zoom so it looks the same size through the lens.  Each marker also keys
the detector's confidence of its joint as a custom property, ``monoskel_confidence`` (0 where the
joint is missing), so the Graph Editor plots it beside the estimate's diagnostics.
"""

from __future__ import annotations

import bpy
import numpy as np

from ..core.camera import film_size_mm, pixels_to_film
from ..core.skeleton import JOINTS, SEGMENTS
from . import compat

IMAGE_PLANE_DISTANCE_M = 1.0
#: Marker size as a fraction of the visible image width.
MARKER_FRACTION = 0.008


def image_plane_points(xy_px: np.ndarray, focal_mm: np.ndarray, image_size, distance: float) -> np.ndarray:
    """Camera-local (Blender axes) points (F, J, 3) on the plane at ``distance`` for pixels (F, J, 2)."""
    film = pixels_to_film(xy_px, image_size)                      # mm, x right, y down
    k = distance / np.asarray(focal_mm, dtype=float)[:, None]     # (F, 1)
    out = np.empty(film.shape[:-1] + (3,))
    out[..., 0] = film[..., 0] * k
    out[..., 1] = -film[..., 1] * k
    out[..., 2] = -distance
    return out


def create_tracks_view(scene, camera_obj, tracks, focal_mm: np.ndarray, name: str, first_frame: int,
                       created: list):
    """Grouping empty (returned) and 17 keyed joint empties under ``camera_obj``."""
    n = min(tracks.n_frames, focal_mm.shape[0])
    xy = tracks.xy[:n]
    present = tracks.present[:n]
    focal = focal_mm[:n]
    points = image_plane_points(xy, focal, tracks.image_size, IMAGE_PLANE_DISTANCE_M)
    film_w = film_size_mm(tracks.image_size)[0]
    marker = MARKER_FRACTION * IMAGE_PLANE_DISTANCE_M * film_w / focal      # (F,)

    root = bpy.data.objects.new(name, None)
    created.append(root)
    scene.collection.objects.link(root)
    root.parent = camera_obj
    root.empty_display_size = 0.0
    root.hide_select = True
    frames_all = np.arange(n) + first_frame
    markers = []
    for j, joint in enumerate(JOINTS):
        obj = bpy.data.objects.new(f"{name}.{joint}", None)
        created.append(obj)
        scene.collection.objects.link(obj)
        obj.parent = root
        markers.append(obj)
        obj.empty_display_type = 'SPHERE'
        obj.show_in_front = True
        obj.hide_select = True
        seen = np.flatnonzero(present[:, j])
        action, made = compat.ensure_action(obj, f"{obj.name}Action")
        if made:
            created.append(action)
        fcurves = compat.ensure_fcurves(obj)
        if seen.size:
            obj.location = [float(v) for v in points[seen[0], j]]
            for axis in range(3):
                compat.set_keys(fcurves, "location", axis, seen + first_frame, points[seen, j, axis],
                                group="Track")
        compat.set_keys(fcurves, "empty_display_size", 0, frames_all, marker, group="Track")
        hidden = (~present[:, j]).astype(float)
        obj.hide_viewport = bool(hidden[0]) if n else True
        compat.set_keys(fcurves, "hide_viewport", 0, frames_all, hidden, group="Track", interpolation='CONSTANT')
        conf = tracks.conf[:n, j].astype(float)
        obj["monoskel_confidence"] = float(conf[0]) if n else 0.0
        obj.id_properties_ui("monoskel_confidence").update(
            min=0.0, max=1.0, description="The tracker's or detector's confidence in this joint (0: missing)")
        compat.set_keys(fcurves, '["monoskel_confidence"]', 0, frames_all, conf, group="Track",
                        interpolation='CONSTANT')
    _create_bone_lines(scene, root, markers, f"{name} Lines", created)
    return root


def _create_bone_lines(scene, root, markers: list, name: str, created: list):
    """A 17-vertex, 16-edge mesh whose vertices are hooked to the markers: the 2D skeleton drawn as lines.

    Every vertex sits at its mesh's origin and is moved by a Hook modifier
    with an identity inverse, which places it at its marker's world position
    whatever the mesh object's own transform; so the lines follow the markers
    with no keys of their own.
    """
    mesh = bpy.data.meshes.new(name)
    created.append(mesh)
    mesh.from_pydata([(0.0, 0.0, 0.0)] * len(JOINTS), [tuple(seg) for seg in SEGMENTS], [])
    obj = bpy.data.objects.new(name, mesh)
    created.append(obj)
    scene.collection.objects.link(obj)
    obj.parent = root
    obj.show_in_front = True
    obj.hide_select = True
    for j, marker in enumerate(markers):
        hook = obj.modifiers.new(f"hook {JOINTS[j]}", 'HOOK')
        hook.object = marker
        hook.vertex_indices_set([j])
    return obj
