"""The :class:`Motion` every synthetic clip is made of: a rigid canonical figure moving over time.

Its own module so that the sources that build one (:mod:`.procedural`, :mod:`.rigid_figure`) and the
loader that picks a source (:mod:`.motion`) all import it without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..skeleton import proportions


@dataclass
class Motion:
    """A canonical 17-joint figure moving over time.

    ``joints`` is (F, 17, 3) metres in a Y-up world with the floor at y = 0;
    ``class_lengths`` is (10,) metres (the figure is rigid: every frame has
    exactly these lengths); ``contacts`` is (F, 2) bool, foot planted on the
    floor and still, columns (left, right).
    """

    name: str
    fps: float
    joints: np.ndarray
    class_lengths: np.ndarray
    contacts: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.joints.shape[0])

    @property
    def proportions(self) -> np.ndarray:
        return proportions(self.class_lengths)
