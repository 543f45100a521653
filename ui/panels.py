"""The "MonoSkel" tab in 3D Viewport > Sidebar (and a small panel in the Movie Clip Editor).

Sub-panels follow the workflow: Input (+ Test Data, Further Views), Camera, Estimate,
Results, Build, Takes, Retarget, Single Image, Export.  What each shows is decided in :mod:`.state`; this
module only renders those rows, so it stays free of logic.
"""

import bpy

from ..operators.movie_clip import find_clip
from . import state


def render(layout, settings, rows) -> None:
    """Draw :class:`state.Row` items into ``layout``."""
    for row in rows:
        if row.kind == "label":
            layout.label(text=row.text, icon=row.icon)
        elif row.kind == "prop":
            line = layout.row()
            line.enabled = row.enabled
            if row.text:
                line.prop(settings, row.attr, text=row.text)
            else:
                line.prop(settings, row.attr)
        elif row.kind == "operator":
            line = layout.row()
            line.enabled = row.enabled
            props = line.operator(row.op, text=row.text, icon=row.icon, depress=row.depress)
            for name, value in row.op_props:
                setattr(props, name, value)
            if row.reason:
                layout.label(text=row.reason, icon="INFO")
        elif row.kind == "progress":
            layout.progress(factor=row.value, type="BAR", text=f"{row.text} ({100 * row.value:.0f}%)")
        elif row.kind == "take_list":
            layout.template_list("MONOSKEL_UL_takes", "", settings, "takes", settings, "take_index", rows=3)
        elif row.kind == "bone_map":
            box = layout.box().column(align=True)
            bones = settings.retarget_target.data
            for item in settings.retarget_map:
                box.prop_search(item, "bone", bones, "bones", text=item.role)
        elif row.kind == "table":
            box = layout.box().column(align=True)
            for r, cells in enumerate(row.cells):
                line = box.row(align=True)
                for cell in cells:
                    line.label(text=cell, icon="NONE")
                if r == 0:
                    box.separator(factor=0.3)


class _SectionPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "MonoSkel"
    bl_parent_id = "MONOSKEL_PT_main"
    section = ""

    def draw(self, context):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = False
        rows = state.section_rows(self.section, context.scene.monoskel, has_clip=find_clip(context) is not None)
        render(self.layout, context.scene.monoskel, rows)


class MONOSKEL_PT_main(bpy.types.Panel):
    bl_label = "MonoSkel"
    bl_idname = "MONOSKEL_PT_main"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "MonoSkel"

    def draw(self, context):
        self.layout.label(text="Tracks > Estimate > Build > Export")


class MONOSKEL_PT_input(_SectionPanel, bpy.types.Panel):
    bl_label = "Input"
    bl_idname = "MONOSKEL_PT_input"
    section = "input"


class MONOSKEL_PT_test_data(_SectionPanel, bpy.types.Panel):
    bl_label = "Test Data (BVH)"
    bl_idname = "MONOSKEL_PT_test_data"
    bl_parent_id = "MONOSKEL_PT_input"
    bl_options = {"DEFAULT_CLOSED"}
    section = "test_data"


class MONOSKEL_PT_views(_SectionPanel, bpy.types.Panel):
    bl_label = "Further Views"
    bl_idname = "MONOSKEL_PT_views"
    bl_parent_id = "MONOSKEL_PT_input"
    bl_options = {"DEFAULT_CLOSED"}
    section = "views"


class MONOSKEL_PT_camera(_SectionPanel, bpy.types.Panel):
    bl_label = "Camera"
    bl_idname = "MONOSKEL_PT_camera"
    section = "camera"


class MONOSKEL_PT_estimate(_SectionPanel, bpy.types.Panel):
    bl_label = "Estimate"
    bl_idname = "MONOSKEL_PT_estimate"
    section = "estimate"


class MONOSKEL_PT_results(_SectionPanel, bpy.types.Panel):
    bl_label = "Results"
    bl_idname = "MONOSKEL_PT_results"
    section = "results"

    def draw(self, context):
        # Tables read better without the property split.
        render(self.layout, context.scene.monoskel, state.section_rows(self.section, context.scene.monoskel))


class MONOSKEL_PT_build(_SectionPanel, bpy.types.Panel):
    bl_label = "Build"
    bl_idname = "MONOSKEL_PT_build"
    section = "build"


class MONOSKEL_UL_takes(bpy.types.UIList):
    """One line per take: active mark, label, show/hide (the take's collection in viewports and renders)."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0, flt_flag=0):
        is_active = index == data.take_active
        row = layout.row(align=True)
        row.label(text=item.name, icon="RADIOBUT_ON" if is_active else "RADIOBUT_OFF")
        if item.collection is not None:
            row.prop(item.collection, "hide_viewport", text="", emboss=False)
            row.prop(item.collection, "hide_render", text="", emboss=False)


class MONOSKEL_PT_takes(_SectionPanel, bpy.types.Panel):
    bl_label = "Takes"
    bl_idname = "MONOSKEL_PT_takes"
    section = "takes"

    def draw(self, context):
        render(self.layout, context.scene.monoskel, state.section_rows(self.section, context.scene.monoskel))


class MONOSKEL_PT_retarget(_SectionPanel, bpy.types.Panel):
    bl_label = "Retarget"
    bl_idname = "MONOSKEL_PT_retarget"
    bl_options = {"DEFAULT_CLOSED"}
    section = "retarget"


class MONOSKEL_PT_single_image(_SectionPanel, bpy.types.Panel):
    bl_label = "Single Image"
    bl_idname = "MONOSKEL_PT_single_image"
    bl_options = {"DEFAULT_CLOSED"}
    section = "single_image"


class MONOSKEL_PT_export(_SectionPanel, bpy.types.Panel):
    bl_label = "Export"
    bl_idname = "MONOSKEL_PT_export"
    section = "export"


class MONOSKEL_PT_clip(bpy.types.Panel):
    """Joint tracks in the Movie Clip Editor (Sidebar > MonoSkel)."""

    bl_label = "MonoSkel Joints"
    bl_idname = "MONOSKEL_PT_clip"
    bl_space_type = "CLIP_EDITOR"
    bl_region_type = "UI"
    bl_category = "MonoSkel"

    def draw(self, context):
        rows = state.section_rows("clip", context.scene.monoskel, has_clip=find_clip(context) is not None)
        render(self.layout, context.scene.monoskel, rows)


classes = (
    MONOSKEL_PT_main,
    MONOSKEL_PT_input,
    MONOSKEL_PT_test_data,
    MONOSKEL_PT_views,
    MONOSKEL_PT_camera,
    MONOSKEL_PT_estimate,
    MONOSKEL_PT_results,
    MONOSKEL_PT_build,
    MONOSKEL_UL_takes,
    MONOSKEL_PT_takes,
    MONOSKEL_PT_retarget,
    MONOSKEL_PT_single_image,
    MONOSKEL_PT_export,
    MONOSKEL_PT_clip,
)
