"""Registration in the style of Blender's own add-ons: ordered, reversible, repeatable."""

import bpy
import pytest


def _is_registered() -> bool:
    return hasattr(bpy.types.Scene, "monoskel") and hasattr(bpy.types, "MONOSKEL_PT_main")


def test_registered_by_the_blender_fixture(empty_scene):
    assert _is_registered()
    assert empty_scene.monoskel.height_m == pytest.approx(1.75)


def test_sidebar_tab_is_in_the_3d_viewport(blender):
    panel = bpy.types.MONOSKEL_PT_main
    assert panel.bl_space_type == "VIEW_3D"
    assert panel.bl_region_type == "UI"
    assert panel.bl_category == "MonoSkel"


def test_unregister_then_register_again_in_one_process(blender, empty_scene):
    try:
        blender.unregister()
        assert not hasattr(bpy.types.Scene, "monoskel")
        assert not hasattr(bpy.types, "MONOSKEL_PT_main")
        assert not hasattr(bpy.context.scene, "monoskel")
        blender.register()
        assert _is_registered()
        bpy.context.scene.monoskel.height_m = 1.6
        assert bpy.context.scene.monoskel.height_m == pytest.approx(1.6)
        blender.unregister()
        blender.register()
        assert _is_registered()
    finally:
        if not _is_registered():  # leave the add-on registered, as the fixture expects it
            blender.register()


def test_second_unregister_raises_instead_of_passing_silently(blender):
    """unregister must never swallow errors: unregistering twice is a bug and must say so."""
    blender.unregister()
    try:
        with pytest.raises((RuntimeError, AttributeError, ValueError)):
            blender.unregister()
    finally:
        if not _is_registered():
            # a half-done second unregister may have left some classes; clear them before re-registering
            _force_clean_unregister()
            blender.register()
    assert _is_registered()


def _force_clean_unregister():
    for name in dir(bpy.types):
        if name.startswith("MONOSKEL_"):
            cls = getattr(bpy.types, name)
            try:
                bpy.utils.unregister_class(cls)
            except RuntimeError:
                pass
    if hasattr(bpy.types.Scene, "monoskel"):
        del bpy.types.Scene.monoskel


def test_failed_register_rolls_back_what_it_registered(blender):
    """A failure half-way through register() must not leave earlier sub-packages registered."""
    from monoskel.ui import panels

    blender.unregister()
    bpy.utils.register_class(panels.MONOSKEL_PT_main)  # makes ui.register() fail: already registered
    try:
        with pytest.raises((ValueError, RuntimeError)):
            blender.register()
        assert not hasattr(bpy.types.Scene, "monoskel"), "properties stayed registered after a failed register"
    finally:
        bpy.utils.unregister_class(panels.MONOSKEL_PT_main)
        if not _is_registered():
            _force_clean_unregister()
            blender.register()
    assert _is_registered()
