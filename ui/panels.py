"""The "MonoSkel" tab in 3D Viewport > Sidebar."""

import bpy


class MONOSKEL_PT_main(bpy.types.Panel):
    bl_label = "MonoSkel"
    bl_idname = "MONOSKEL_PT_main"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "MonoSkel"

    def draw(self, context):
        settings = context.scene.monoskel
        self.layout.prop(settings, "height_m")


classes = (MONOSKEL_PT_main,)
