"""Retargeting onto the animator's rig in Blender: read the rig, store its bone map, bake keys.

``rig_io`` turns an armature object into :class:`core.retarget.TargetRig`; ``bone_map_store`` keeps a
rig's bone map in the .blend (and as preset files); ``apply`` runs the core solve and writes the keys.
"""
