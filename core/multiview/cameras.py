"""Calibrated pinhole cameras for several synchronized views, and their calibration JSON.

One camera per view: square pixels, the principal point at the image centre (what phones and webcams
deliver after their own correction), a focal length in pixels, and a pose: ``rotation`` takes world
axes to camera axes (x right, y down, z forward, as in :mod:`core.camera`) and ``position`` is the
camera centre in the world.  A world point ``X`` projects to ``f * Y[:2] / Y[2] + centre`` with
``Y = rotation @ (X - position)``.

The calibration file (``"format": "multiview-calibration"``, version 1) holds one such entry per
view, in the order of the tracks files; :func:`read_calibration` refuses anything else in one line.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

FORMAT_NAME = "multiview-calibration"
FORMAT_VERSION = 1


@dataclass
class ViewCamera:
    name: str
    image_size: tuple[float, float]
    focal_px: float
    rotation: np.ndarray          # (3, 3) world -> camera axes
    position: np.ndarray          # (3,) camera centre, world

    def __post_init__(self) -> None:
        self.rotation = np.asarray(self.rotation, dtype=float).reshape(3, 3)
        self.position = np.asarray(self.position, dtype=float).reshape(3)
        if not (math.isfinite(self.focal_px) and self.focal_px > 0):
            raise InputError(f"camera {self.name!r}: focal length must be a positive number of pixels")
        if not np.allclose(self.rotation @ self.rotation.T, np.eye(3), atol=1e-4) or np.linalg.det(self.rotation) < 0:
            raise InputError(f"camera {self.name!r}: rotation must be a proper rotation matrix")

    @property
    def centre(self) -> np.ndarray:
        return np.array([self.image_size[0] / 2.0, self.image_size[1] / 2.0])

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) in this camera's axes."""
        return (np.asarray(points, dtype=float) - self.position) @ self.rotation.T

    def project(self, points: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of world points (..., 3); NaN behind the camera."""
        y = self.to_camera(points)
        z = y[..., 2:3]
        uv = self.focal_px * y[..., :2] / np.where(z > 1e-9, z, np.nan) + self.centre
        return uv

    def projection_matrix(self) -> np.ndarray:
        """(3, 4) ``K [R | -R c]``."""
        k = np.array([[self.focal_px, 0, self.centre[0]], [0, self.focal_px, self.centre[1]], [0, 0, 1.0]])
        return k @ np.hstack([self.rotation, -(self.rotation @ self.position)[:, None]])

    def focal_mm(self) -> float:
        """The focal length in the project's 36 mm film units (:mod:`core.camera`)."""
        from ..camera import mm_per_pixel

        return float(self.focal_px * mm_per_pixel(self.image_size))

    def to_dict(self) -> dict:
        return {"name": self.name, "image_size": [float(v) for v in self.image_size],
                "focal_px": float(self.focal_px), "rotation": self.rotation.tolist(),
                "position": self.position.tolist()}

    @classmethod
    def from_dict(cls, d: dict, where: str = "") -> ViewCamera:
        try:
            return cls(name=str(d.get("name", "")), image_size=tuple(float(v) for v in d["image_size"]),
                       focal_px=float(d["focal_px"]), rotation=np.array(d["rotation"], dtype=float),
                       position=np.array(d["position"], dtype=float))
        except InputError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{where}camera entry needs name, image_size, focal_px, rotation (3x3) and "
                             f"position (3): {exc}") from None


def write_calibration(cameras: list[ViewCamera], path: str | os.PathLike) -> None:
    doc = {"format": FORMAT_NAME, "version": FORMAT_VERSION, "cameras": [c.to_dict() for c in cameras]}
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1)


def read_calibration(path: str | os.PathLike) -> list[ViewCamera]:
    """The cameras of a calibration JSON, in view order."""
    where = f"{os.fspath(path)}: "
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except OSError as exc:
        raise InputError(f"{where}cannot read calibration: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{where}not JSON: {exc.msg} (line {exc.lineno})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
        raise InputError(f"{where}not a {FORMAT_NAME} file")
    if doc.get("version") != FORMAT_VERSION:
        raise InputError(f"{where}{FORMAT_NAME} version {doc.get('version')!r} is not supported (only 1)")
    cams = doc.get("cameras")
    if not isinstance(cams, list) or not cams:
        raise InputError(f"{where}no cameras")
    return [ViewCamera.from_dict(c, where) for c in cams]


def look_at(position, target, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """World -> camera rotation of a camera at ``position`` looking at ``target`` (Y-up world), level."""
    fwd = np.asarray(target, float) - np.asarray(position, float)
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, -np.asarray(up, float))      # camera x: right in the image
    right /= np.linalg.norm(right)
    down = np.cross(fwd, right)                          # camera y: down in the image
    return np.stack([right, down, fwd])
