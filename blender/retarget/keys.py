"""Writing a retarget into the rig: its one MonoSkel action, rotation keys in the bone's own mode,
and the way back if a bake fails.  Shared by the direct bake (:mod:`.apply`) and the evaluated one
(:mod:`.evaluated`).

The keys go into an action of their own, ``<rig>|MonoSkel`` (tagged ``monoskel_retarget``); running
again replaces that action, once the new one is whole, instead of adding another.  An action the rig had before is kept
(a fake user, so saving does not drop it) and can be put back from the Action editor.
"""

from __future__ import annotations

from contextlib import contextmanager

import bpy
import numpy as np

from ...core.retarget.curves import euler_continuous
from .. import compat

TAG = "monoskel_retarget"


def _action_for(obj, created: list):
    """A new, empty MonoSkel action on the rig (recorded in ``created``); an action the rig had that was
    not ours keeps a fake user so saving does not drop it."""
    anim = obj.animation_data or obj.animation_data_create()
    previous = anim.action
    if previous is not None and not previous.get(TAG):
        previous.use_fake_user = True
    anim.action = None
    action = bpy.data.actions.new(f"{obj.name}|MonoSkel")
    action[TAG] = True
    created.append(action)
    anim.action = action
    return action


@contextmanager
def baking(obj):
    """``with baking(obj) as (action, fcurves):`` - the keys go into a new action.  If the body
    succeeds, a MonoSkel action the rig had before is removed and the new one takes its name (running
    again rewrites, it does not pile up); if it fails, the rig gets its previous action and rotation
    modes back, whatever it was, and the new action goes again."""
    created: list = []
    anim = obj.animation_data
    old_action = anim.action if anim is not None else None
    old_modes = {pb.name: pb.rotation_mode for pb in obj.pose.bones}
    try:
        action = _action_for(obj, created)
        yield action, compat.ensure_fcurves(obj)
    except BaseException:
        for block in created:
            try:
                bpy.data.actions.remove(block)
            except ReferenceError:
                pass
        if obj.animation_data is not None:
            obj.animation_data.action = old_action
        for pb in obj.pose.bones:
            pb.rotation_mode = old_modes[pb.name]
        raise
    if old_action is not None and old_action.get(TAG) and old_action.users == 0:
        name = old_action.name
        bpy.data.actions.remove(old_action)
        action.name = name


def key_rotation(obj, fcurves, name: str, frames, q: np.ndarray) -> None:
    """Key quaternions ``q`` (F, 4) (w, x, y, z) at ``frames`` on bone ``name`` in its rotation mode:
    quaternion keys, Euler keys without jumps (any order), axis-angle bones switched to quaternions."""
    pb = obj.pose.bones[name]
    path = f'pose.bones["{name}"]'
    if pb.rotation_mode == 'AXIS_ANGLE':
        pb.rotation_mode = 'QUATERNION'
    if pb.rotation_mode == 'QUATERNION':
        for c in range(4):
            compat.set_keys(fcurves, f"{path}.rotation_quaternion", c, frames, q[:, c], group=name)
    else:
        euler = euler_continuous(q, pb.rotation_mode)
        for c in range(3):
            compat.set_keys(fcurves, f"{path}.rotation_euler", c, frames, euler[:, c], group=name)


def key_location(fcurves, name: str, frames, location: np.ndarray) -> None:
    """Key a bone's local location (F, 3) at ``frames``."""
    for c in range(3):
        compat.set_keys(fcurves, f'pose.bones["{name}"].location', c, frames, location[:, c], group=name)
