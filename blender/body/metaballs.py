"""D'Apuzzo et al.'s body model on the built armature: ellipsoidal metaballs, one per bone.

Each bone carries one ellipsoid along it, as long as the bone and as thick as an average adult's
limb there (:data:`GIRTH_RADIUS`, metres at 1.75 m, scaled by the armature's own height), parented to
the bone so the body moves with the motion.  All ellipsoids are elements of metaball objects of one
family (``<name>``, ``<name>.001``, ...), which Blender melts into one surface: what the camera sees of
the body, for checking contact and silhouette against the footage.
"""

from __future__ import annotations

import bpy
from mathutils import Vector

from ..build_armature import BONES

#: Radius (metres, 1.75 m adult) across the bone, and the other across (front to back), per bone:
#: rounded from adult anthropometric girths (thigh ~55 cm round, calf ~37, upper arm ~30, forearm ~26,
#: waist ~80, chest ~95, neck ~37, head ~57).
GIRTH_RADIUS: dict[str, tuple[float, float]] = {
    "spine_lower": (0.15, 0.11), "spine_upper": (0.16, 0.11), "neck": (0.055, 0.055), "head": (0.08, 0.10),
    "hip.L": (0.08, 0.09), "hip.R": (0.08, 0.09), "thigh.L": (0.085, 0.085), "thigh.R": (0.085, 0.085),
    "shin.L": (0.055, 0.06), "shin.R": (0.055, 0.06), "clavicle.L": (0.05, 0.05), "clavicle.R": (0.05, 0.05),
    "upper_arm.L": (0.045, 0.045), "upper_arm.R": (0.045, 0.045), "forearm.L": (0.04, 0.037),
    "forearm.R": (0.04, 0.037),
}
REFERENCE_HEIGHT_M = 1.75
#: Polygonisation size of the surface, metres (viewport and render).
RESOLUTION_M = 0.03
#: The surface of a lone ellipsoid lies at this share of its size at the threshold and stiffness used
#: (measured on the thigh: 0.57), so the element radius makes up for it.
SURFACE_GAIN = 1.0 / 0.57


def body_objects(armature) -> list:
    """The metaball objects of a body built on ``armature``."""
    return [o for o in armature.children if o.get("monoskel_body") and o.type == 'META']


def unique_family(name: str) -> str:
    """A metaball family name no object uses yet (a family is every ``<name>``, ``<name>.NNN``)."""
    taken = {o.name.split(".")[0] for o in bpy.data.objects}
    if name not in taken:
        return name
    k = 2
    while f"{name} {k}" in taken:
        k += 1
    return f"{name} {k}"


def replace_body(scene, armature, *, height_m: float | None = None) -> list:
    """Build a body on ``armature`` and remove the one it had; all or nothing (a failure removes what it
    made and leaves the old body).  Objects go into the armature's collection."""
    from ..build import remove_created

    old = body_objects(armature)
    created: list = []
    collection = armature.users_collection[0] if armature.users_collection else scene.collection
    try:
        objs = build_body(collection, armature, unique_family(f"{armature.name} Body"), created, height_m=height_m)
    except BaseException:
        remove_created(created)
        raise
    for o in old:
        data = o.data
        bpy.data.objects.remove(o)
        if data is not None and data.users == 0:
            bpy.data.metaballs.remove(data)
    return objs


def build_body(collection, armature, name: str, created: list, *, height_m: float | None = None) -> list:
    """Metaball objects in ``collection`` (the family's first is the one that shows the surface) parented
    to ``armature``'s bones; everything made is appended to ``created``.  ``height_m``: the figure's
    height (default: the armature's own ``monoskel_height_m`` or 1.75 m)."""
    height = height_m or float(armature.get("monoskel_height_m", REFERENCE_HEIGHT_M))
    k = height / REFERENCE_HEIGHT_M / armature.matrix_world.to_scale()[0]      # metres -> armature units
    objects = []
    for i, (bone_name, _, _, _) in enumerate(BONES):
        bone = armature.data.bones.get(bone_name)
        if bone is None or bone.length <= 1e-6:
            continue
        data = bpy.data.metaballs.new(name if i == 0 else f"{name}.{i:03d}")
        created.append(data)
        data.resolution = RESOLUTION_M
        data.render_resolution = RESOLUTION_M
        data.threshold = 0.6
        obj = bpy.data.objects.new(name if i == 0 else f"{name}.{i:03d}", data)
        created.append(obj)
        collection.objects.link(obj)
        across, depth = GIRTH_RADIUS.get(bone_name, (0.05, 0.05))
        el = data.elements.new(type='ELLIPSOID')
        el.radius = SURFACE_GAIN
        # the element's own axes: x across, y along the bone, z front to back (bone space)
        el.size_x = across * k
        el.size_y = 0.5 * bone.length + 0.2 * across * k
        el.size_z = depth * k
        el.stiffness = 2.0
        obj.parent = armature
        obj.parent_type = 'BONE'
        obj.parent_bone = bone_name
        # a bone child sits at the bone's tail: step back half the bone along its length
        obj.location = Vector((0.0, -0.5 * bone.length, 0.0))
        obj["monoskel_body"] = bone_name
        objects.append(obj)
    return objects
