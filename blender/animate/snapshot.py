"""What a run puts into the scene, remembered before it does, so a failure part way puts it all back.

The stored tracks and estimate (hidden Texts), the sidebar's settings and summary, the frame range, rate
and render size, the scene camera and clip, the timeline markers, the takes (a take made after the
snapshot is deleted with everything it owns), the target rig's action and the clip's tracking camera.
Blender's undo does the same for a whole operator, but not for a step that fails inside one.
"""

from __future__ import annotations

import bpy

from .. import scene_data
from ..review import takes as _takes

_LENS = ("units", "sensor_width", "focal_length")
_RENDER = ("fps", "fps_base", "resolution_x", "resolution_y", "resolution_percentage")


def _settings_values(settings) -> dict:
    """Every plain (non-collection, writable) property of ``scene.monoskel``."""
    out = {}
    for prop in settings.bl_rna.properties:
        if prop.identifier == "rna_type" or prop.is_readonly or prop.type == "COLLECTION":
            continue
        value = getattr(settings, prop.identifier)
        out[prop.identifier] = tuple(value) if getattr(prop, "is_array", False) else value
    return out


class SceneSnapshot:
    """The scene's MonoSkel state now; :meth:`restore` brings it back."""

    def __init__(self, scene, target=None, clip=None):
        self.scene_name = scene.name
        settings = scene.monoskel
        self.texts = {}
        for kind in scene_data.KINDS:
            name = scene.get(scene_data._prop(kind))
            text = bpy.data.texts.get(name) if name else None
            self.texts[kind] = None if text is None else (text.name, text.as_string())
        self.values = _settings_values(settings)
        self.bone_map = [(item.role, item.bone) for item in settings.retarget_map]
        self.n_takes = len(settings.takes)
        self.frames = (scene.frame_start, scene.frame_end, scene.frame_current)
        self.render = tuple(getattr(scene.render, name) for name in _RENDER)
        self.camera, self.clip = scene.camera, scene.active_clip
        self.markers = [(m.name, m.frame) for m in scene.timeline_markers]
        self.target = target
        self.clip_name = None if clip is None else clip.name
        self.lens = None if clip is None else tuple(getattr(clip.tracking.camera, n) for n in _LENS)
        anim = getattr(target, "animation_data", None)
        self.action = None if anim is None else anim.action

    def restore(self) -> None:
        scene = bpy.data.scenes[self.scene_name]
        settings = scene.monoskel
        while len(settings.takes) > self.n_takes:
            _takes.delete_take(scene, len(settings.takes) - 1)
        for kind, kept in self.texts.items():
            if kept is None:
                scene_data.clear(scene, kind)
                continue
            name, body = kept
            text = bpy.data.texts.get(name) or bpy.data.texts.new(name)
            text.clear()
            text.from_string(body)
            scene[scene_data._prop(kind)] = text.name
        now = _settings_values(settings)
        for name, value in self.values.items():
            if now.get(name) == value:
                continue
            try:
                setattr(settings, name, value)
            except (AttributeError, TypeError, ValueError, ReferenceError):
                pass            # a pointer to something deleted since: it stays cleared
        settings.retarget_map.clear()
        for role, bone in self.bone_map:
            item = settings.retarget_map.add()
            item.role, item.bone = role, bone
        scene.frame_start, scene.frame_end = self.frames[:2]
        scene.frame_set(self.frames[2])
        for name, value in zip(_RENDER, self.render, strict=True):
            setattr(scene.render, name, value)
        scene.camera, scene.active_clip = self.camera, self.clip
        keep = set(self.markers)
        for marker in [m for m in scene.timeline_markers if (m.name, m.frame) not in keep]:
            scene.timeline_markers.remove(marker)
        have = {(m.name, m.frame) for m in scene.timeline_markers}
        for name, frame in self.markers:
            if (name, frame) not in have:
                scene.timeline_markers.new(name, frame=frame)
        self._restore_action()
        clip = bpy.data.movieclips.get(self.clip_name) if self.clip_name else None
        if clip is not None:
            for name, value in zip(_LENS, self.lens, strict=True):
                setattr(clip.tracking.camera, name, value)

    def _restore_action(self) -> None:
        target = self.target
        if target is None:
            return
        anim = target.animation_data
        now = None if anim is None else anim.action
        if now is self.action or now == self.action:
            return
        if anim is None:
            anim = target.animation_data_create()
        anim.action = self.action
        if now is not None and now.users == 0:
            bpy.data.actions.remove(now)
