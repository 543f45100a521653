"""Build an estimate into the scene: the scaled armature with its motion, the camera, the tracks.

The public builders (:func:`build_armature`, :func:`build_camera`,
:func:`build_all`) are transactional: each records every datablock it makes
and, if anything fails midway (bad data, a cancelling ``report`` callback,
a Blender error), removes them all and restores the scene settings it touched
before re-raising, so the user never finds a half-built rig.

Where things go in the world.  Joints and the camera come in frame 0's camera
coordinates (x right, y down, z forward, metres for a person of
``est.height_m``).  ``est.diagnostics["world_from_cam0"]`` (4x4) maps them to
the Z-up world when a method estimated the ground.  Without it the default is
a camera looking horizontally along +Y world (x right, z up), i.e.
world = (x, z_cam, -y_cam), placed above the origin at the height that puts
the lowest ankle of the clip at ankle height over the floor z = 0 (camera at
the origin when there is no 3D motion).  When the armature is built for a
different height than the estimate's, the whole scene (joints and camera
position) is scaled by ``height_m / est.height_m`` — monocular reconstruction
is only defined up to that scale anyway.

Frames: estimate frame i is scene frame ``first_frame + i`` (default 1).
"""

from __future__ import annotations

import math
import re

import bpy
import numpy as np

from ..core.camera import film_size_mm
from ..core.errors import InputError
from ..core.skeleton import ANKLE_HEIGHT_FRACTION, JOINT_INDEX, N_JOINTS, class_lengths_for_height
from . import build_armature as _arm
from . import build_camera as _cam
from . import build_tracks_view as _tracks
from . import diagnostics as _diag
from .review import markers as _review

BONES = _arm.BONES
FIRST_FRAME = 1
_DEFAULT_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # world from cam0


# ----------------------------------------------------------------------------- world placement

def _scene_scale(est, height_m: float) -> float:
    if est.height_m and est.height_m > 0:
        return float(height_m) / float(est.height_m)
    return 1.0


def joints_cam0(est) -> tuple[np.ndarray, np.ndarray]:
    """(frame indices, joints (n, 17, 3)) of the frames whose 3D joints are complete and finite."""
    idx = np.array([i for i, fr in enumerate(est.frames) if fr.joints_3d is not None], dtype=int)
    if idx.size == 0:
        return idx, np.zeros((0, N_JOINTS, 3))
    try:  # one conversion for the whole clip (fast on long clips) ...
        joints = np.array([est.frames[i].joints_3d for i in idx], dtype=float)
        ok = joints.shape == (idx.size, N_JOINTS, 3)
    except ValueError:
        ok = False
    if not ok:  # ... and a frame-by-frame look only to name the bad frame
        for i in idx:
            j = np.asarray(est.frames[i].joints_3d, dtype=object)
            if j.shape != (N_JOINTS, 3):
                raise ValueError(f"frame {i}: joints_3d must be 17 x [x, y, z], got shape {j.shape}")
        raise ValueError("joints_3d must be 17 x [x, y, z] numbers in every frame")
    finite = np.isfinite(joints).all(axis=(1, 2))
    return idx[finite], joints[finite]


def world_from_cam0(est, height_m: float) -> np.ndarray:
    """4x4 matrix taking frame-0 camera coordinates (estimate scale) to the built world (metres)."""
    k = _scene_scale(est, height_m)
    given = (est.diagnostics or {}).get("world_from_cam0")
    m = np.eye(4)
    if given is not None:
        g = np.asarray(given, dtype=float)
        if g.shape != (4, 4) or not np.isfinite(g).all():
            raise ValueError(f"diagnostics.world_from_cam0 must be a finite 4x4 matrix, got shape {g.shape}")
        m[:3, :3] = g[:3, :3]
        m[:3, 3] = g[:3, 3] * k
    else:
        m[:3, :3] = _DEFAULT_AXES
        _, joints = joints_cam0(est)
        if joints.size:
            ankles = joints[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]] @ _DEFAULT_AXES.T
            m[2, 3] = ANKLE_HEIGHT_FRACTION * height_m - k * float(ankles[..., 2].min())
    m[:3, :3] *= k
    return m


def world_joints(est, height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(frame indices, world joints (n, 17, 3)) for the frames with 3D joints."""
    idx, joints = joints_cam0(est)
    m = world_from_cam0(est, height_m)
    return idx, joints @ m[:3, :3].T + m[:3, 3]


def _rotation_only(m: np.ndarray) -> np.ndarray:
    r = m[:3, :3]
    return r / np.cbrt(np.linalg.det(r))


# ----------------------------------------------------------------------------- transactions

class _SceneState:
    """The scene settings a build changes, restored if the build fails."""

    def __init__(self, scene):
        r = scene.render
        self.scene = scene
        self.values = (scene.frame_start, scene.frame_end, r.fps, r.fps_base, r.resolution_x, r.resolution_y,
                       r.resolution_percentage, r.pixel_aspect_x, r.pixel_aspect_y, scene.camera)

    def restore(self):
        s, r = self.scene, self.scene.render
        (s.frame_start, s.frame_end, r.fps, r.fps_base, r.resolution_x, r.resolution_y,
         r.resolution_percentage, r.pixel_aspect_x, r.pixel_aspect_y, s.camera) = self.values


_COLLECTIONS = (
    (bpy.types.Object, "objects"), (bpy.types.Armature, "armatures"), (bpy.types.Camera, "cameras"),
    (bpy.types.Action, "actions"), (bpy.types.Collection, "collections"), (bpy.types.Mesh, "meshes"),
)


def remove_created(created: list) -> None:
    """Remove datablocks in reverse order of creation (objects before their data)."""
    for marker in [d for d in created if isinstance(d, bpy.types.TimelineMarker)][::-1]:
        for scene in bpy.data.scenes:
            if any(m == marker for m in scene.timeline_markers):
                scene.timeline_markers.remove(marker)
                break
    objects = [d for d in created if isinstance(d, bpy.types.Object)]
    others = [d for d in created if not isinstance(d, (bpy.types.Object, bpy.types.TimelineMarker))]
    for block in objects[::-1] + others[::-1]:
        for kind, attr in _COLLECTIONS:
            if isinstance(block, kind):
                try:
                    getattr(bpy.data, attr).remove(block)
                except ReferenceError:  # already gone (e.g. removed with its owner)
                    pass
                break


def remove_built(obj) -> None:
    """Remove an object a builder returned, with its children, their data and every action they use.

    For undoing a finished build (e.g. the second step of a two-step build
    failed): covers the camera data's lens action and the track markers too.
    """
    blocks, stack = [], [obj]
    while stack:
        o = stack.pop()
        blocks.append(o)
        stack.extend(o.children)
    extra = []
    for o in blocks:
        for owner in (o, o.data):
            anim = getattr(owner, "animation_data", None) if owner is not None else None
            if anim is not None and anim.action is not None and anim.action not in extra:
                extra.append(anim.action)
        if o.data is not None:
            extra.append(o.data)
    remove_created(extra + blocks)


def _tree(obj) -> list:
    """``obj`` and all its descendants."""
    out, stack = [], [obj]
    while stack:
        o = stack.pop()
        out.append(o)
        stack.extend(o.children)
    return out


_SUFFIX = re.compile(r"^(.*)\.\d{3,}$")


def settle_names(obj) -> None:
    """Give ``obj``'s tree, its data and its actions back their plain names ("MonoSkel.001" -> "MonoSkel",
    "MonoSkel.001Action" -> "MonoSkelAction") where the plain name is free: a rebuild that replaced the
    previous objects keeps their names."""
    renamed = {}
    others = []
    for o in _tree(obj):
        m = _SUFFIX.match(o.name)
        if m and bpy.data.objects.get(m.group(1)) is None:
            renamed[o.name] = m.group(1)
            o.name = m.group(1)
        for owner in (o, o.data):
            anim = getattr(owner, "animation_data", None) if owner is not None else None
            if anim is not None and anim.action is not None:
                others.append((anim.action, bpy.data.actions))
        kind = {"ARMATURE": bpy.data.armatures, "CAMERA": bpy.data.cameras, "MESH": bpy.data.meshes}.get(o.type)
        if kind is not None and o.data is not None:
            others.append((o.data, kind))
    for block, collection in others:
        name = block.name
        for old, new in sorted(renamed.items(), key=lambda kv: -len(kv[0])):
            if old in name:
                name = name.replace(old, new, 1)
                break
        else:
            m = _SUFFIX.match(name)
            name = m.group(1) if m else name
        if name != block.name and collection.get(name) is None:
            block.name = name


def replace_built(old, new) -> None:
    """After a successful rebuild: remove the previous build ``old`` (its tree, data and actions) and let
    ``new`` take its names, so building again replaces instead of piling up copies."""
    if old is None or new is None or old == new:
        return
    try:
        old.name  # noqa: B018 - a removed object raises ReferenceError
    except ReferenceError:
        return
    remove_built(old)
    settle_names(new)


def _move_objects(created: list, scene, collection) -> None:
    """Link the objects a build made into ``collection`` instead of the scene's master collection."""
    if collection is None or collection == scene.collection:
        return
    for obj in created:
        if isinstance(obj, bpy.types.Object):
            if obj.name not in collection.objects:
                collection.objects.link(obj)
            if obj.name in scene.collection.objects:
                scene.collection.objects.unlink(obj)


def _transaction(scene, fn, collection=None):
    created: list = []
    state = _SceneState(scene)
    try:
        result = fn(created)
        _move_objects(created, scene, collection)
        scene.frame_set(scene.frame_current)  # evaluate once so matrix_world and poses are current for callers
        return result
    except BaseException:
        try:
            mode_obj = bpy.context.view_layer.objects.active if bpy.context.view_layer else None
            if mode_obj is not None and mode_obj in created and mode_obj.mode != 'OBJECT':
                bpy.ops.object.mode_set(mode='OBJECT')
        except (RuntimeError, ReferenceError, AttributeError):
            pass
        remove_created(created)
        state.restore()
        raise


# ----------------------------------------------------------------------------- scene timing

def _stored_tracks(scene):
    try:
        from .scene_data import load_tracks

        return load_tracks(scene)
    except Exception:  # stored data is only a convenience here; never block a build on it
        return None


def _view_tracks(scene, est) -> list:
    """The further views' tracks on the first view's clock (``diagnostics.frame_offsets``), one per
    further camera of ``est``, or [] when the scene's stored views are not this estimate's."""
    try:
        from .scene_data import load_views

        views, _ = load_views(scene)
    except Exception:  # stored data is only a convenience here; never block a build on it
        return []
    from ..core.multiview.sync import aligned_pixels
    from ..core.tracks import Tracks

    diag = est.diagnostics or {}
    cams = diag.get("cameras") or []
    offsets = diag.get("frame_offsets") or [0] * len(cams)
    if len(views) != len(cams) - 1 or len(offsets) != len(cams):
        return []
    n = len(est.frames)
    out = []
    for view, offset in zip(views, offsets[1:]):
        xy = aligned_pixels(view, int(offset), n)
        seen = np.isfinite(xy).all(axis=-1)
        out.append(Tracks(xy, seen.astype(float), view.fps, view.image_size, source=view.source))
    return out


def _image_size(scene, est, tracks):
    if tracks is not None:
        return tracks.image_size
    size = (est.diagnostics or {}).get("image_size")
    if isinstance(size, (list, tuple)) and len(size) == 2:
        return float(size[0]), float(size[1])
    r = scene.render
    return float(r.resolution_x), float(r.resolution_y)


def _clip_fps(est, tracks) -> float | None:
    if tracks is not None:
        return tracks.fps
    fps = (est.diagnostics or {}).get("fps")
    return float(fps) if isinstance(fps, (int, float)) and fps > 0 else None


def set_scene_timing(scene, n_frames: int, fps: float | None, first_frame: int = FIRST_FRAME) -> None:
    """Frame range covering the clip and, when known, the clip's frame rate (fps / fps_base)."""
    scene.frame_start = first_frame
    scene.frame_end = first_frame + max(n_frames, 1) - 1
    if fps is not None and fps > 0:
        whole = max(1, int(round(fps)))
        scene.render.fps = whole
        scene.render.fps_base = whole / float(fps)


def _set_resolution(scene, image_size) -> None:
    r = scene.render
    r.resolution_x = max(4, int(round(image_size[0])))
    r.resolution_y = max(4, int(round(image_size[1])))
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0


# ----------------------------------------------------------------------------- builders

def _armature(scene, est, height_m, name, with_motion, first_frame, created):
    if not (height_m > 0 and math.isfinite(height_m)):
        raise ValueError(f"height must be a positive number of metres, got {height_m!r}")
    lengths = class_lengths_for_height(est.proportions_vector(), height_m)
    if not np.all(np.isfinite(lengths)) or np.any(lengths <= 0):
        raise ValueError("the estimate's proportions do not give positive bone lengths")
    obj = _arm.create_armature(scene, lengths, name, created)
    if with_motion:
        idx, joints = world_joints(est, height_m)
        if idx.size:
            _arm.key_pose(obj, joints, idx + first_frame, created)
    _diag.key_diagnostics(obj, est, first_frame, created)
    obj["monoskel_height_m"] = float(height_m)
    obj["monoskel_method"] = str(est.method)
    return obj


def _camera(scene, est, tracks, name, height_m, first_frame, created, with_tracks_view=True):
    if tracks is None:
        tracks = _stored_tracks(scene)
        if tracks is not None and tracks.n_frames != len(est.frames):
            tracks = None  # stored tracks from another clip: do not draw them over this estimate
    elif tracks.n_frames != len(est.frames):
        raise InputError(f"the estimate has {len(est.frames)} frames but the tracks have {tracks.n_frames}; "
                         "estimate these tracks again")
    image_size = _image_size(scene, est, tracks)
    film_size_mm(image_size)  # validates the size
    m = world_from_cam0(est, height_m)
    obj = _cam.create_camera(scene, est, image_size, _rotation_only(m), m[:3, 3], name, first_frame, created)
    further = _cam.view_cameras(est)
    view_tracks = _view_tracks(scene, est) if further and with_tracks_view else []
    for k, (_view, size, lens, rot, centre) in enumerate(further, start=2):
        # the further views of a multi-view estimate stand still where they filmed from
        still = _cam.create_static_camera(scene, size, _rotation_only(m) @ rot.T, m[:3, :3] @ centre + m[:3, 3],
                                          lens, f"{name} {k}", created)
        if view_tracks:       # each view's own tracks, seen through its camera
            _tracks.create_tracks_view(scene, still, view_tracks[k - 2], np.full(len(est.frames), lens),
                                       f"{name} {k} Tracks", first_frame, created)
    _cam.mark_spells(scene, (est.diagnostics or {}).get("spells"), first_frame, created)
    _review.mark_problems(scene, est, first_frame, created)
    _set_resolution(scene, image_size)
    scene.camera = obj
    view = None
    if tracks is not None and with_tracks_view:
        focal = np.array([fr.focal_mm for fr in est.frames], dtype=float)
        view = _tracks.create_tracks_view(scene, obj, tracks, focal, f"{name} Tracks", first_frame, created)
    return obj, view, tracks


def build_armature(scene, est, *, height_m: float = 1.75, name: str = "MonoSkel", with_motion: bool = True,
                   first_frame: int = FIRST_FRAME, collection=None):
    """Armature scaled to ``height_m`` from the estimated proportions, keyed on the 3D motion.

    ``collection`` (default: the scene's master collection) receives the objects, e.g. a take's.
    """
    def run(created):
        obj = _armature(scene, est, height_m, name, with_motion, first_frame, created)
        set_scene_timing(scene, len(est.frames), _clip_fps(est, _stored_tracks(scene)), first_frame)
        return obj

    return _transaction(scene, run, collection)


def build_camera(scene, est, tracks=None, *, name: str = "MonoSkel Camera", height_m: float | None = None,
                 first_frame: int = FIRST_FRAME, with_tracks_view: bool = True, collection=None):
    """Camera keyed per frame; with ``tracks`` (or tracks stored on the scene) the joint markers too.

    ``with_tracks_view=False`` builds the camera alone, without the markers.

    ``height_m`` (default: the estimate's own height) must match the
    armature's so that camera and figure share one world scale.
    """
    height = height_m if height_m is not None else (est.height_m or 1.75)

    def run(created):
        obj, _, used_tracks = _camera(scene, est, tracks, name, height, first_frame, created, with_tracks_view)
        set_scene_timing(scene, len(est.frames), _clip_fps(est, used_tracks), first_frame)
        return obj

    return _transaction(scene, run, collection)


def build_all(scene, est, tracks=None, *, height_m: float = 1.75, report=None, name: str = "MonoSkel",
              first_frame: int = FIRST_FRAME, collection=None) -> dict:
    """Armature, camera and tracks view in one transaction -> {"armature", "camera", "tracks"}.

    ``report(level, message)`` receives progress lines; an exception raised by
    it (e.g. a cancel) aborts the build and removes everything built so far.
    """
    def say(level, message):
        if report is not None:
            report(level, message)

    def run(created):
        arm = _armature(scene, est, height_m, name, True, first_frame, created)
        n_posed = int(joints_cam0(est)[0].size)
        say('INFO', f"armature '{arm.name}': {len(BONES)} bones, {n_posed} of {len(est.frames)} frames posed")
        cam, view, used_tracks = _camera(scene, est, tracks, f"{name} Camera", height_m, first_frame, created)
        say('INFO', f"camera '{cam.name}': focal {est.focal_mm:.1f} mm, {len(est.frames)} frames"
            + ("" if view is None else ", tracks shown through it"))
        set_scene_timing(scene, len(est.frames), _clip_fps(est, used_tracks), first_frame)
        if n_posed == 0:
            say('WARNING', "the estimate has no 3D joints: the armature stands in its rest pose")
        for warning in (est.diagnostics or {}).get("warnings", []):
            say('WARNING', str(warning))
        return {"armature": arm, "camera": cam, "tracks": view}

    return _transaction(scene, run, collection)
