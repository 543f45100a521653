"""Points no camera could have seen: far outside the picture.

A detector may report a coordinate past the image edge for a joint just out of frame (that is
useful), but not one a whole image width away, and never 1e300.  Those become missing.
"""

from __future__ import annotations

import numpy as np


def far_outside(xy: np.ndarray, image_size: tuple[float, float], margin: float) -> np.ndarray:
    """(F, 17) bool: the point lies more than ``margin`` image sizes outside the picture."""
    w, h = image_size
    x, y = xy[..., 0], xy[..., 1]
    with np.errstate(invalid="ignore"):
        bad = (x < -margin * w) | (x > (1 + margin) * w) | (y < -margin * h) | (y > (1 + margin) * h)
    return bad & np.isfinite(xy).all(axis=-1)
