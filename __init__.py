"""MonoSkel: a scaled skeleton, the camera and the motion from 2D joint tracks.

This file is the extension's entry point.  It imports ``bpy`` only inside
:func:`register` / :func:`unregister` so that the pure-data ``core`` package
can be imported by plain Python, ``python -m core`` and pytest without
Blender.  Registration follows Blender's own add-ons: each sub-package owns
one ordered class list; property groups register first and everything is
undone in reverse.
"""


def _modules():
    # Imported lazily: these modules need bpy.
    from . import operators, properties, ui

    return (properties, operators, ui)


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
