"""Review: jump to a frame the estimate flags (the sidebar's worst-fitting frames)."""

from __future__ import annotations

import bpy

from . import common


class MONOSKEL_OT_jump_to_frame(bpy.types.Operator):
    """Go to this frame to see why it fits poorly"""

    bl_idname = "monoskel.jump_to_frame"
    bl_label = "Jump to Frame"
    bl_options = {"INTERNAL"}

    frame: bpy.props.IntProperty(name="Frame")

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("estimate",))

    def execute(self, context):
        context.scene.frame_set(int(self.frame))
        return {"FINISHED"}


classes = (MONOSKEL_OT_jump_to_frame,)
