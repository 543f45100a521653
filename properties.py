"""Scene-level settings and state of the extension (``scene.monoskel``).

Registered first; everything else reads and writes through this group.
"""

import bpy


class MONOSKEL_PG_settings(bpy.types.PropertyGroup):
    height_m: bpy.props.FloatProperty(
        name="Subject Height",
        description="Standing height of the person; the armature is scaled to it",
        default=1.75, min=0.3, max=3.0, unit="LENGTH",
    )


classes = (MONOSKEL_PG_settings,)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.Scene.monoskel = bpy.props.PointerProperty(type=MONOSKEL_PG_settings)


def unregister():
    del bpy.types.Scene.monoskel
    _unregister_classes()
