"""The paper's experiment inside Blender: a known motion, filmed by a virtual camera.

A motion (a BVH file or a built-in walk/run) is filmed by the core's generator
(:func:`core.synthetic.synth.synthesize`) with a chosen camera schedule, pixel noise and
drop-out.  The result is the same kind of 2D tracks a detector would give, plus
the exact truth (proportions, camera, 3D joints), so the animator can run the
estimator and compare per class in the Results panel.

The ground-truth armature shows what was filmed:

* a BVH file goes through Blender's own importer (``import_anim.bvh``), keyed
  so that the motion's first frame is on scene frame 1 like the tracks, and
  scaled by the same factor the core used to bring the figure to the truth's
  standing height (it stays where the file puts it: the core also recentres
  the motion, the importer does not);
* a built-in motion has no file, so the truth is turned into an estimate-shaped
  record and built with the same builder the estimate uses
  (:func:`blender.build.build_armature`): the truth armature and an estimated
  one are then directly comparable, bone for bone.

Either way nothing is left behind if a step fails.
"""

from __future__ import annotations

import os

import bpy

from ..core.errors import InputError
from ..core.synthetic.motion import BUILTIN_PREFIX, load_motion
from ..core.synthetic.truth import truth_as_estimate  # noqa: F401 - the builders' tests build the truth through it

TRUTH_NAME = "MonoSkel Truth"


def _new_blocks(before: dict) -> list:
    """Datablocks created since ``before`` (objects first, so they go before their data)."""
    made = []
    for attr in ("objects", "armatures", "actions"):
        made.extend(b for b in getattr(bpy.data, attr) if b.as_pointer() not in before[attr])
    return made


def _snapshot() -> dict:
    return {attr: {b.as_pointer() for b in getattr(bpy.data, attr)} for attr in ("objects", "armatures", "actions")}


def _remove(blocks: list) -> None:
    for block in blocks:
        for attr in ("objects", "armatures", "actions"):
            collection = getattr(bpy.data, attr)
            try:
                if block.name in collection and collection[block.name] == block:
                    collection.remove(block)
                    break
            except ReferenceError:
                break


def bvh_file_height(path: str) -> float:
    """Standing height of the BVH's figure in the file's own units, measured as the core measures it.

    The core rescales every BVH motion so this height becomes the truth's height; giving
    Blender's importer the same ratio as ``global_scale`` makes both armatures the same size.
    """
    from ..core.io.bvh import read_bvh
    from ..core.io.bvh_mapping import build_mapping, canonical_positions
    from ..core.skeleton import class_lengths_from_segments, segment_lengths, standing_height

    bvh = read_bvh(path)
    points = canonical_positions(bvh, build_mapping(bvh))
    return float(standing_height(class_lengths_from_segments(segment_lengths(points).mean(axis=0))))


def import_truth_bvh(context, path: str, height_m: float, *, first_frame: int = 1):
    """Blender's BVH importer on ``path``, scaled to ``height_m``; returns (object, created blocks).

    ``first_frame`` is the scene frame of the file's first frame (0 when the core dropped an
    inserted T-pose frame, so that the motion's frame 0 lands on scene frame 1 like the tracks).
    """
    file_height = bvh_file_height(path)
    if not file_height > 0:
        raise InputError(f"{path}: the figure has no height")
    before = _snapshot()
    try:
        result = bpy.ops.import_anim.bvh(
            filepath=path, target="ARMATURE", global_scale=height_m / file_height, frame_start=first_frame,
            use_fps_scale=False, update_scene_fps=False, update_scene_duration=False, rotate_mode="NATIVE",
        )
    except RuntimeError as exc:
        _remove(_new_blocks(before))
        raise InputError(f"{path}: Blender's BVH importer failed: {' '.join(str(exc).split())}") from None
    made = _new_blocks(before)
    arms = [b for b in made if isinstance(b, bpy.types.Object) and b.type == "ARMATURE"]
    if "FINISHED" not in result or not arms:
        _remove(made)
        raise InputError(f"{path}: Blender's BVH importer made no armature")
    obj = arms[0]
    obj.name = TRUTH_NAME
    return obj, made


def import_bvh_test_data(context, source: str, *, kinds=("pan", "tilt", "zoom"), noise_px: float = 1.0,
                         dropout: float = 0.0, seed: int = 0, max_frames: int | None = None,
                         height_m: float = 1.75, report=None):
    """Film ``source`` (a .bvh path or ``builtin:NAME``) and build its truth armature.

    Returns ``(tracks, truth, armature_object)``.  Storing the tracks and the truth on
    the scene is the caller's job (the operator), so this function can be reused by
    ``batch.py``.  Raises :class:`InputError` for bad input; creates nothing then.
    """
    from ..core.synthetic.synth import synthesize

    def say(level, message):
        if report is not None:
            report(level, message)

    is_file = not source.startswith(BUILTIN_PREFIX)
    if is_file:
        source = bpy.path.abspath(source) if source.startswith("//") else source
        if not source:
            raise InputError("no BVH file chosen")
        if not os.path.isfile(source):
            raise InputError(f"{source}: no such BVH file")
    kinds = tuple(kinds) or ("still",)
    motion = load_motion(source, height_m=height_m, max_frames=max_frames or None)
    tracks, truth = synthesize(motion, kinds=kinds, noise_px=noise_px, dropout=dropout, seed=seed)
    say("INFO", f"filmed {motion.name}: {tracks.n_frames} frames, camera {', '.join(kinds)}")
    if is_file:
        dropped = int(motion.meta.get("dropped_first_frames", 0))
        armature, _ = import_truth_bvh(context, source, float(truth.height_m), first_frame=1 - dropped)
    else:
        from .build import build_armature

        armature = build_armature(context.scene, truth_as_estimate(truth), height_m=float(truth.height_m),
                                  name=TRUTH_NAME, with_motion=True, first_frame=1)
    return tracks, truth, armature


def remove_armature(obj) -> None:
    """Undo :func:`import_bvh_test_data`'s armature (used when storing the data fails afterwards)."""
    data = obj.data
    anim = obj.animation_data
    action = anim.action if anim is not None else None
    bpy.data.objects.remove(obj)
    if data is not None and data.users == 0:
        bpy.data.armatures.remove(data)
    if action is not None and action.users == 0:
        bpy.data.actions.remove(action)
