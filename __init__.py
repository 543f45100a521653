"""MonoSkel: a scaled skeleton, the camera and the motion from 2D joint tracks.

This file is the extension's entry point (metadata lives in ``blender_manifest.toml``).  It
imports ``bpy`` only inside :func:`register` / :func:`unregister` so that the pure-data
``core`` package can be imported by plain Python, ``python -m core`` and pytest without
Blender.  Registration follows Blender's own add-ons: each sub-package owns one ordered
class list; property groups register first and everything is undone in reverse.
"""


def _modules():
    # Imported lazily: these modules need bpy.  Order matters: properties first (panels and
    # operators read ``scene.monoskel``), then operators, then the UI that calls them.
    from . import operators, properties, ui

    return (properties, operators, ui)


def register():
    """Register every sub-package in order.

    If one fails, the ones already registered are unregistered again before the error is
    re-raised, so a failed enable leaves no half-registered classes behind and the add-on can
    be enabled again after the cause is fixed.
    """
    done = []
    try:
        for module in _modules():
            module.register()
            done.append(module)
    except BaseException:
        for module in reversed(done):
            module.unregister()
        raise


def unregister():
    """Undo :func:`register` in reverse order.

    No exception is swallowed: a failure here is a bug (e.g. a class registered twice or a
    property left behind) and must be seen, not hidden.
    """
    for module in reversed(_modules()):
        module.unregister()
