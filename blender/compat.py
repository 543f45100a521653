"""The one place that knows how Blender 4.2 and 5.0 differ where MonoSkel touches them.

Animation data, the sequencer's strip collection and the render output's media type (the last two
for decoding footage, :mod:`blender.pose_detection`).

Blender 4.2-4.3 keep F-curves directly on the action (``action.fcurves``).
Blender 4.4 introduced *slotted* (layered) actions: an action holds slots,
layers and keyframe strips, and the F-curves of one animated ID live in the
strip's channelbag for that ID's slot; 4.4/4.5 still proxy ``action.fcurves``,
5.0 removed it.  Every builder asks :func:`ensure_fcurves` for "the collection
to add F-curves to" and writes keys with :func:`set_keys` (bulk
``keyframe_points.add`` + ``foreach_set``, never one ``keyframe_insert`` per
key, which is orders of magnitude slower on long clips).
"""

from __future__ import annotations

import bpy
import numpy as np

#: True on Blender 4.4+, where every action is slotted/layered.  Decided by version, not by
#: ``hasattr(Action, "slots")``: 4.3 already exposes an experimental, differently shaped slots API.
SLOTTED_ACTIONS = bpy.app.version >= (4, 4, 0)

_INTERPOLATION_ENUM = None


def _interpolation_code(name: str) -> int:
    """Integer value of an interpolation enum item, as ``foreach_set('interpolation')`` wants it."""
    global _INTERPOLATION_ENUM
    if _INTERPOLATION_ENUM is None:
        items = bpy.types.Keyframe.bl_rna.properties["interpolation"].enum_items
        _INTERPOLATION_ENUM = {item.identifier: item.value for item in items}
    return _INTERPOLATION_ENUM[name]


def ensure_action(id_block, name: str | None = None):
    """The action animating ``id_block`` (object, armature, camera data, ...), created if absent.

    Returns ``(action, created)`` so callers that must roll back know whether
    the action is theirs to remove.
    """
    anim = id_block.animation_data or id_block.animation_data_create()
    created = False
    if anim.action is None:
        anim.action = bpy.data.actions.new(name or f"{id_block.name}Action")
        created = True
    action = anim.action
    if SLOTTED_ACTIONS and anim.action_slot is None:
        slot = None
        for candidate in action.slots:  # reuse a slot meant for this kind of ID
            if candidate.target_id_type in (id_block.id_type, "UNSPECIFIED"):
                slot = candidate
                break
        if slot is None:
            slot = action.slots.new(id_type=id_block.id_type, name=id_block.name)
        anim.action_slot = slot
    return action, created


def _channelbag(action, slot):
    try:
        from bpy_extras.anim_utils import action_ensure_channelbag_for_slot  # 5.0+
    except ImportError:
        action_ensure_channelbag_for_slot = None
    if action_ensure_channelbag_for_slot is not None:
        return action_ensure_channelbag_for_slot(action, slot)
    layer = action.layers[0] if len(action.layers) else action.layers.new("Layer")
    strip = layer.strips[0] if len(layer.strips) else layer.strips.new(type='KEYFRAME')
    return strip.channelbag(slot, ensure=True)


def ensure_fcurves(id_block, action_name: str | None = None):
    """The F-curve collection to add keys for ``id_block`` to (action or channelbag)."""
    action, _ = ensure_action(id_block, action_name)
    if SLOTTED_ACTIONS:
        return _channelbag(action, id_block.animation_data.action_slot).fcurves
    return action.fcurves


def find_fcurves(id_block):
    """The existing F-curve collection of ``id_block`` or None (never creates anything)."""
    anim = id_block.animation_data
    if anim is None or anim.action is None:
        return None
    if not SLOTTED_ACTIONS:
        return anim.action.fcurves
    slot = anim.action_slot
    if slot is None:
        return None
    for layer in anim.action.layers:
        for strip in layer.strips:
            bag = strip.channelbag(slot)
            if bag is not None:
                return bag.fcurves
    return None


def _new_fcurve(fcurves, data_path: str, index: int, group: str | None):
    """A new F-curve in ``group``, whichever way this Blender names the group.

    4.2-4.3 ``action.fcurves.new(action_group=)``; 5.0 ``channelbag.fcurves.new(group_name=)``;
    4.4-4.5 channelbag ``fcurves.new`` takes no group, so the group is made in the collection's
    owner (``fcurves.data``, the channelbag) and assigned afterwards.
    """
    params = fcurves.bl_rna.functions["new"].parameters
    for keyword in ("group_name", "action_group"):
        if group and keyword in params:
            return fcurves.new(data_path, index=index, **{keyword: group})
    fcurve = fcurves.new(data_path, index=index)
    if group:
        bag = fcurves.data
        fcurve.group = bag.groups.get(group) or bag.groups.new(group)
    return fcurve


def set_keys(fcurves, data_path: str, index: int, frames, values, group: str | None = None,
             interpolation: str = 'LINEAR'):
    """Replace the keys of one F-curve with ``values`` at ``frames`` in one bulk write.

    ``frames`` and ``values`` are 1-D sequences of equal length; an existing
    F-curve for ``data_path``/``index`` is emptied first so builders can be
    re-run.  Returns the F-curve.
    """
    frames = np.asarray(frames, dtype=np.float32).ravel()
    values = np.asarray(values, dtype=np.float32).ravel()
    if frames.shape != values.shape:
        raise ValueError(f"{data_path}[{index}]: {frames.size} frames but {values.size} values")
    fcurve = fcurves.find(data_path, index=index)
    if fcurve is None:
        fcurve = _new_fcurve(fcurves, data_path, index, group)
    else:
        fcurve.keyframe_points.clear()
    n = frames.size
    fcurve.keyframe_points.add(n)
    if n:
        co = np.empty((n, 2), dtype=np.float32)
        co[:, 0] = frames
        co[:, 1] = values
        fcurve.keyframe_points.foreach_set("co", co.ravel())
        code = _interpolation_code(interpolation)
        fcurve.keyframe_points.foreach_set("interpolation", np.full(n, code, dtype=np.int32))
    fcurve.update()
    return fcurve


def get_keys(id_block, data_path: str, index: int = 0):
    """``(frames, values)`` float arrays of one F-curve of ``id_block``, or None if it has none."""
    fcurves = find_fcurves(id_block)
    if fcurves is None:
        return None
    fcurve = fcurves.find(data_path, index=index)
    if fcurve is None:
        return None
    n = len(fcurve.keyframe_points)
    co = np.empty(2 * n, dtype=np.float32)
    fcurve.keyframe_points.foreach_get("co", co)
    co = co.reshape(n, 2).astype(float)
    return co[:, 0], co[:, 1]


def fcurve_paths(id_block) -> set[tuple[str, int]]:
    """``{(data_path, index)}`` of every F-curve animating ``id_block`` (for tests and checks)."""
    fcurves = find_fcurves(id_block)
    return set() if fcurves is None else {(fc.data_path, fc.array_index) for fc in fcurves}


def sequencer_strips(editor):
    """The sequence editor's top-level strip collection (5.0 renamed ``sequences`` to ``strips``)."""
    return editor.strips if hasattr(editor, "strips") else editor.sequences


def set_output_format(image_settings, file_format: str) -> None:
    """Set a render output format; 5.0 first needs the media type (``IMAGE`` or ``VIDEO`` for FFMPEG)."""
    if hasattr(image_settings, "media_type"):
        image_settings.media_type = "VIDEO" if file_format == "FFMPEG" else "IMAGE"
    image_settings.file_format = file_format
