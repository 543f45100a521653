"""What the MediaPipe CSV and JSON readers share: landmark names and the pixel conversion.

MediaPipe Pose gives 33 landmarks with x, y normalised to the image (0..1,
may fall slightly outside when a point is off-screen), a depth z (unused)
and a ``visibility`` in 0..1 that becomes the confidence (1 when a file has
no visibility).  Pixels = normalised x * width, y * height, so the image size
is needed.
"""

from __future__ import annotations

import numpy as np

from ...tracks import Tracks
from ._canonical import canonical_tracks
from .keypoint_sets import MEDIAPIPE_33, MEDIAPIPE_NAMES, used

N_LANDMARKS = len(MEDIAPIPE_NAMES)
_BY_NAME = {name: i for i, name in enumerate(MEDIAPIPE_NAMES)}


def landmark_index(key: str) -> int | None:
    """Index of a landmark written as its number (``"11"``) or name (``"Left_Shoulder"``)."""
    key = key.strip().lower().replace(" ", "_").replace("-", "_")
    if key.isdigit():
        i = int(key)
        return i if i < N_LANDMARKS else None
    return _BY_NAME.get(key)


def landmarks_to_tracks(norm_xy: np.ndarray, visibility: np.ndarray, *, fps: float, image_size, source: str,
                        meta: dict) -> Tracks:
    """Tracks from (F, 33, 2) normalised positions (NaN = no detection) and (F, 33) visibilities."""
    idx, names = used(MEDIAPIPE_33)
    scale = np.array(image_size, dtype=float)
    return canonical_tracks(norm_xy[:, idx] * scale, visibility[:, idx], names, fps=fps, image_size=image_size,
                            source=source, meta=meta)
