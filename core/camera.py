"""The pinhole camera model shared by the generator, the estimators and Blender.

Conventions (used everywhere, including RESULT.json):

* Image: pixels, origin top-left, x right, y down, square pixels.
* Film: Peng & Li's 35 mm normalisation.  The image is scaled, keeping its
  aspect ratio, to fit centred inside a 36 x 24 mm frame; film coordinates are
  millimetres from the image centre, x right, y down.  Focal lengths are in
  millimetres of that 36 mm-wide film ("35 mm equivalent"), which is what a
  Blender camera with ``sensor_width = 36`` uses when the image is 3:2; for
  other aspect ratios the fitted width is :func:`film_size_mm`.
* Camera axes: x right, y down, z forward (the viewing direction).  A point
  with camera coordinates ``X`` projects to film ``f * X[:2] / X[2]``.
* Camera motion: the camera stays at one position and rotates/zooms.  For a
  static scene point, ``X_i = R_i @ X_0`` where ``X_0`` are its coordinates in
  frame 0's camera and ``R_i`` is frame i's rotation (``R_0 = I``), stored as a
  rotation vector in degrees.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

FILM_WIDTH_MM = 36.0
FILM_HEIGHT_MM = 24.0
DEFAULT_FOCAL_MM = 50.0


def mm_per_pixel(image_size: tuple[float, float]) -> float:
    """Millimetres of normalised film per image pixel (fit inside 36 x 24)."""
    w, h = float(image_size[0]), float(image_size[1])
    if w <= 0 or h <= 0:
        raise ValueError(f"image size must be positive, got {image_size!r}")
    return min(FILM_WIDTH_MM / w, FILM_HEIGHT_MM / h)


def film_size_mm(image_size: tuple[float, float]) -> tuple[float, float]:
    """Width and height in mm that the image occupies on the normalised film."""
    k = mm_per_pixel(image_size)
    return float(image_size[0]) * k, float(image_size[1]) * k


def pixels_to_film(uv: np.ndarray, image_size: tuple[float, float]) -> np.ndarray:
    """Pixel coordinates (..., 2) to film millimetres from the centre (..., 2)."""
    uv = np.asarray(uv, dtype=float)
    k = mm_per_pixel(image_size)
    centre = np.array([image_size[0], image_size[1]], dtype=float) / 2.0
    return (uv - centre) * k


def film_to_pixels(xy_mm: np.ndarray, image_size: tuple[float, float]) -> np.ndarray:
    """Inverse of :func:`pixels_to_film`."""
    xy_mm = np.asarray(xy_mm, dtype=float)
    k = mm_per_pixel(image_size)
    centre = np.array([image_size[0], image_size[1]], dtype=float) / 2.0
    return xy_mm / k + centre


def project_to_film(points_cam: np.ndarray, focal_mm) -> np.ndarray:
    """Perspective projection of camera-frame points (..., 3) to film mm (..., 2).

    ``focal_mm`` broadcasts against the leading axes (a scalar, or one value
    per frame shaped (F, 1) for points shaped (F, J, 3)).
    """
    p = np.asarray(points_cam, dtype=float)
    f = np.asarray(focal_mm, dtype=float)
    return f[..., None] * p[..., :2] / p[..., 2:3]


def project_to_pixels(points_cam: np.ndarray, focal_mm, image_size) -> np.ndarray:
    """Perspective projection of camera-frame points straight to pixels."""
    return film_to_pixels(project_to_film(points_cam, focal_mm), image_size)


def film_rays(xy_mm: np.ndarray, focal_mm) -> np.ndarray:
    """Unnormalised viewing rays (x, y, f) for film points (..., 2)."""
    xy = np.asarray(xy_mm, dtype=float)
    f = np.broadcast_to(np.asarray(focal_mm, dtype=float), xy.shape[:-1])
    return np.concatenate([xy, f[..., None]], axis=-1)


def rotation_matrix(rotvec_deg: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from rotation vectors in degrees (..., 3)."""
    r = np.asarray(rotvec_deg, dtype=float)
    flat = r.reshape(-1, 3)
    mats = Rotation.from_rotvec(np.radians(flat)).as_matrix()
    return mats.reshape(r.shape[:-1] + (3, 3))


def rotvec_deg(matrices: np.ndarray) -> np.ndarray:
    """Rotation vectors in degrees (..., 3) from rotation matrices (..., 3, 3)."""
    m = np.asarray(matrices, dtype=float)
    flat = m.reshape(-1, 3, 3)
    return np.degrees(Rotation.from_matrix(flat).as_rotvec()).reshape(m.shape[:-2] + (3,))


def pan_tilt_roll_matrix(pan_deg, tilt_deg, roll_deg=0.0) -> np.ndarray:
    """Camera rotation for a pan (about camera y), tilt (about x) and roll (about z).

    Positive pan turns the view to the right, positive tilt turns it down
    (y is down).  Returned so that ``X_i = R @ X_0`` as in the module docstring.
    """
    pan, tilt, roll = (np.radians(np.asarray(a, dtype=float)) for a in (pan_deg, tilt_deg, roll_deg))
    pan, tilt, roll = np.broadcast_arrays(pan, tilt, roll)
    # Turning the camera by Q (in frame-0 axes) maps static points by R = Q^T.
    q = Rotation.from_euler("YXZ", np.stack([pan, -tilt, roll], axis=-1).reshape(-1, 3))
    return np.transpose(q.as_matrix(), (0, 2, 1)).reshape(pan.shape + (3, 3))
