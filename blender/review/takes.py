"""Takes: every build of an estimate belongs to one, in a collection of its own.

A take holds what one build made (the armature with its action, the camera with its lens curve and
the tracks view under it), a copy of the estimate it was built from (a hidden Text) and a label
naming the tracks, the method and the time.  Building again replaces the *active* take's objects and
keeps their names (:func:`build_take`); a new take leaves the others beside it.  A take deleted
(:func:`delete_take`) takes every data-block it owns with it.  The take list lives in
``scene.monoskel.takes``; ``scene.monoskel.armature`` / ``camera`` always point at the active take's
objects, so Export and the rest of the sidebar follow the active take.

Objects of take 1 are called "MonoSkel", "MonoSkel Camera", ...; of take N "MonoSkel N", ... so two
takes never fight over names.
"""

from __future__ import annotations

import time
import uuid

import bpy
import numpy as np

from ...core.result import estimate_from_dict, estimate_to_dict
from ...core.review.take_compare import TakeComparison, compare_takes
from ...core.skeleton import class_lengths_for_height
from .. import build
from ..build_camera import add_markers
from ..scene_data import read_json_text, write_json_text
from . import markers as _markers

BASE_NAME = "MonoSkel"


def object_prefix(number: int) -> str:
    return BASE_NAME if number == 1 else f"{BASE_NAME} {number}"


def take_label(number: int, source: str, method: str, when: str) -> str:
    """The take's name in the list and of its collection: number, tracks, method, time."""
    parts = [p for p in (source, method, when) if p]
    return f"Take {number}: " + " · ".join(parts) if parts else f"Take {number}"


def _source_name(settings) -> str:
    source = (settings.tracks_source or "").replace("\\", "/").rsplit("/", 1)[-1]
    return source[:24]          # the label stays within Blender's 63 characters for a collection name


def active_index(settings) -> int:
    """Index of the active take, -1 when there is none."""
    i = settings.take_active
    return i if 0 <= i < len(settings.takes) else -1


def active_take(settings):
    i = active_index(settings)
    return settings.takes[i] if i >= 0 else None


def _alive(block) -> bool:
    if block is None:
        return False
    try:
        block.name  # noqa: B018 - a removed data-block raises ReferenceError
    except ReferenceError:
        return False
    return True


# ----------------------------------------------------------------------------- the take's estimate

def store_take_estimate(take, est) -> None:
    """Keep a copy of the estimate a take was built from (for Compare, Make Active and reloads)."""
    text = take.estimate if _alive(take.estimate) else None
    if text is None:
        text = bpy.data.texts.new(f".monoskel_take_{take.number}.json")
        take.estimate = text
    write_json_text(text, estimate_to_dict(est))


def load_take_estimate(take):
    if not _alive(take.estimate):
        return None
    return estimate_from_dict(read_json_text(take.estimate))


# ----------------------------------------------------------------------------- creating and building

def _new_take(scene, settings):
    """A new, empty take with its collection (linked under the scene's collection)."""
    number = max((t.number for t in settings.takes), default=0) + 1
    take = settings.takes.add()
    take.number = number
    take.name = take_label(number, _source_name(settings), "", "")
    coll = bpy.data.collections.new(take.name)
    scene.collection.children.link(coll)
    take.collection = coll
    if number == 1 and len(settings.takes) == 1:
        # A file built before takes existed: its objects become take 1's, so the build replaces them.
        take.armature = settings.armature
        take.camera = settings.camera
    return take


def _drop_take_entry(settings, index: int) -> None:
    """Remove take ``index``'s collection, Text and list entry (its objects must be gone or moved out)."""
    take = settings.takes[index]
    if _alive(take.collection):
        bpy.data.collections.remove(take.collection)
    if _alive(take.estimate):
        bpy.data.texts.remove(take.estimate)
    settings.takes.remove(index)
    _fix_active_after_removal(settings, index)


def _index_of(settings, take) -> int:
    return next(i for i, t in enumerate(settings.takes) if t == take)


def build_take(scene, est, tracks=None, *, new: bool = False, armature: bool = True, camera: bool = True,
               with_motion: bool = True, with_tracks_view: bool = True, report=None) -> dict:
    """Build ``est`` into the active take (or, with ``new`` or no take yet, into a new one).

    Returns {"armature": obj, "camera": obj} for what was built.  All or nothing: if any step fails,
    what it built is removed, a take made for it goes again, and the previous objects stay.
    """
    settings = scene.monoskel
    take = None if new else active_take(settings)
    made = take is None
    if made:
        take = _new_take(scene, settings)
    prefix = object_prefix(take.number)
    height, first = settings.height_m, settings.tracks_first_frame
    built: dict = {}
    try:
        if armature:
            built["armature"] = build.build_armature(scene, est, height_m=height, name=prefix,
                                                     with_motion=with_motion, first_frame=first,
                                                     collection=take.collection)
        if camera:
            built["camera"] = build.build_camera(scene, est, tracks, name=f"{prefix} Camera", height_m=height,
                                                 first_frame=first, with_tracks_view=with_tracks_view,
                                                 collection=take.collection)
        store_take_estimate(take, est)
    except BaseException:
        for obj in built.values():
            build.remove_built(obj)
        if made:                     # its first build failed: the take goes with it
            _drop_take_entry(settings, _index_of(settings, take))
        raise
    for attr, obj in built.items():
        build.replace_built(getattr(take, attr) if _alive(getattr(take, attr)) else None, obj)
        setattr(take, attr, obj)
    take.method = str(est.method)
    take.source = _source_name(settings)
    take.height_m = float(height)
    take.built_at = time.strftime("%H:%M:%S")
    take.build_id = uuid.uuid4().hex
    take.name = take_label(take.number, take.source, take.method, take.built_at)
    take.collection.name = take.name
    index = _index_of(settings, take)
    make_active(scene, index, est)
    settings.take_index = index
    if report is not None:
        report('INFO', f"{take.name}: " + ", ".join(f"'{o.name}'" for o in built.values()))
    return built


def make_active(scene, index: int, est=None) -> None:
    """Make take ``index`` the one Build replaces and Export uses: its camera films the scene and the
    timeline shows its estimate's markers (``est``: that estimate, when the caller has it)."""
    settings = scene.monoskel
    take = settings.takes[index]
    settings.take_active = index
    settings.armature = take.armature if _alive(take.armature) else None
    settings.camera = take.camera if _alive(take.camera) else None
    if settings.camera is not None:
        scene.camera = settings.camera
    est = est if est is not None else load_take_estimate(take)
    keep = set() if est is None else _markers.expected_markers(est, settings.tracks_first_frame)
    _markers.prune_markers(scene, keep)
    if est is not None and settings.camera is not None:
        add_markers(scene, sorted(keep, key=lambda m: (m[1], m[0])), [])


# ----------------------------------------------------------------------------- deleting

def _fix_active_after_removal(settings, removed: int) -> None:
    if settings.take_active > removed:
        settings.take_active -= 1
    elif settings.take_active == removed:
        settings.take_active = -1
    settings.take_index = min(max(settings.take_index - (settings.take_index > removed), 0),
                              max(len(settings.takes) - 1, 0))


def delete_take(scene, index: int) -> str:
    """Remove take ``index`` and every data-block it owns; returns its name.

    Objects someone else put into the take's collection are not the take's: they move to the scene's
    collection instead of being deleted.
    """
    settings = scene.monoskel
    take = settings.takes[index]
    name = take.name
    was_active = index == active_index(settings)
    for obj in (take.armature, take.camera):
        if _alive(obj):
            build.remove_built(obj)
    coll = take.collection
    if _alive(coll):
        for obj in list(coll.objects):
            if obj.name not in scene.collection.objects:
                scene.collection.objects.link(obj)
        for child in list(coll.children):
            scene.collection.children.link(child)
    _drop_take_entry(settings, index)
    if was_active:
        if len(settings.takes):
            make_active(scene, len(settings.takes) - 1)
        else:
            settings.armature = settings.camera = None
            _markers.prune_markers(scene, set())
    return name


# ----------------------------------------------------------------------------- comparing

def _posed(take, est):
    height = take.height_m or est.height_m or 1.75
    frames, joints = build.world_joints(est, height)
    return class_lengths_for_height(est.proportions_vector(), height), frames, joints


#: Custom property keyed on take B's armature by :func:`compare`: its per-frame difference from take A.
DIFF_PROPERTY = "monoskel_take_difference_mm"


def compare(scene, index_a: int, index_b: int) -> TakeComparison:
    """Compare take B with take A (bone lengths as built, joints per frame in the scene).

    The per-frame mean joint distance is also keyed on B's armature as :data:`DIFF_PROPERTY`, so the
    Graph Editor plots where the takes part.
    """
    settings = scene.monoskel
    a, b = settings.takes[index_a], settings.takes[index_b]
    est_a, est_b = load_take_estimate(a), load_take_estimate(b)
    if est_a is None or est_b is None:
        from ...core.errors import InputError

        raise InputError(f"{(a if est_a is None else b).name} has no estimate stored; build it again")
    result = compare_takes(*_posed(a, est_a), *_posed(b, est_b))
    arm = b.armature if _alive(b.armature) else None
    if arm is not None and result.frames.size:
        from .. import compat

        fcurves = compat.ensure_fcurves(arm)
        arm[DIFF_PROPERTY] = float(result.frame_mm[0])
        arm.id_properties_ui(DIFF_PROPERTY).update(
            description=f"Mean distance of this take's joints from {a.name}'s, millimetres", min=0.0)
        compat.set_keys(fcurves, f'["{DIFF_PROPERTY}"]', 0, result.frames + settings.tracks_first_frame,
                        np.asarray(result.frame_mm), group="MonoSkel diagnostics")
    return result
