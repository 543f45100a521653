"""An armature object as the core's :class:`~core.retarget.rig.TargetRig` (armature space, parents first)."""

from __future__ import annotations

import numpy as np

from ...core.errors import InputError
from ...core.retarget.rig import TargetRig


def target_rig(obj) -> TargetRig:
    """The rest pose of armature object ``obj`` (its bones in an order where parents come first)."""
    if obj is None or getattr(obj, "type", None) != 'ARMATURE':
        raise InputError("choose an armature to retarget onto")
    bones = list(obj.data.bones)
    if not bones:
        raise InputError(f"'{obj.name}' has no bones")
    order, seen = [], set()
    stack = [b for b in bones if b.parent is None][::-1]
    while stack:
        b = stack.pop()
        if b.name in seen:
            continue
        seen.add(b.name)
        order.append(b)
        stack.extend(list(b.children)[::-1])
    index = {b.name: i for i, b in enumerate(order)}
    parents = [index[b.parent.name] if b.parent is not None else -1 for b in order]
    head = np.array([tuple(b.head_local) for b in order], dtype=float)
    tail = np.array([tuple(b.tail_local) for b in order], dtype=float)
    rest = np.array([[list(row)[:3] for row in b.matrix_local.to_3x3()] for b in order], dtype=float)
    return TargetRig([b.name for b in order], parents, head, tail, rest)
