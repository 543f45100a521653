"""The target armature's rest pose as plain arrays: what the retargeting needs to know of a rig.

Everything is in the armature's own space (Blender's ``bone.matrix_local``): for a rig imported at
0.01 scale (FBX from Mixamo) that is centimetres, and the retargeting scales the source to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class TargetRig:
    """``names`` (n,), ``parents`` (n,) index or -1, rest ``head``/``tail`` (n, 3) and rest bone
    orientation ``rest`` (n, 3, 3) (columns: the bone's x, y (head to tail), z axes); parents precede
    children."""

    names: list[str]
    parents: np.ndarray
    head: np.ndarray
    tail: np.ndarray
    rest: np.ndarray

    def __post_init__(self):
        self.parents = np.asarray(self.parents, dtype=int)
        self.head = np.asarray(self.head, dtype=float)
        self.tail = np.asarray(self.tail, dtype=float)
        self.rest = np.asarray(self.rest, dtype=float)
        n = len(self.names)
        if self.parents.shape != (n,) or self.head.shape != (n, 3) or self.tail.shape != (n, 3) \
                or self.rest.shape != (n, 3, 3):
            raise ValueError("TargetRig: names, parents, head, tail and rest must describe the same bones")
        for i, p in enumerate(self.parents):
            if p >= i:
                raise ValueError(f"TargetRig: bone {self.names[i]!r} comes before its parent")
        self.index = {name: i for i, name in enumerate(self.names)}

    @property
    def n(self) -> int:
        return len(self.names)

    def children(self, i: int) -> list[int]:
        return [int(c) for c in np.flatnonzero(self.parents == i)]

    def ancestors(self, i: int) -> list[int]:
        """Parent, grandparent, ... of bone ``i`` (nearest first)."""
        out = []
        p = int(self.parents[i])
        while p >= 0:
            out.append(p)
            p = int(self.parents[p])
        return out

    def length(self, i: int) -> float:
        return float(np.linalg.norm(self.tail[i] - self.head[i]))


def rest_from_head_tail_roll(head, tail, z_hint) -> np.ndarray:
    """A bone orientation (3, 3) with y along head -> tail and z as close to ``z_hint`` as it can be
    (how Blender's bone roll is usually set); for building rigs in tests and tools."""
    y = np.asarray(tail, dtype=float) - np.asarray(head, dtype=float)
    if np.linalg.norm(y) == 0:
        raise ValueError("a bone needs a length (head and tail differ)")
    y /= np.linalg.norm(y)
    z = np.asarray(z_hint, dtype=float) - np.dot(z_hint, y) * y
    if np.linalg.norm(z) < 1e-9:
        z = np.cross(y, [1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.cross(y, [0.0, 1.0, 0.0])
    z /= np.linalg.norm(z)
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=1)
