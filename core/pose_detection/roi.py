"""Rotated square regions of an image: how BlazePose looks at a person.

Both BlazePose networks see a square crop of the frame.  A region is a
centre and side in image pixels plus a rotation (radians, y down): the crop's
normalised point (u, v) in [0, 1]^2 sits in the image at

    centre + R(rotation) @ ((u - 0.5) * side, (v - 0.5) * side),  R = [[c, -s], [s, c]]

which is MediaPipe's convention, so its landmark projection and ours agree.
Sampling is bilinear on OpenCV's grid, as the reference pipeline's affine
warp: output pixel u samples the region at u / N, and integer image
coordinates are pixel centres.  The networks were trained on crops made that
way; sampling at pixel centres instead ((u + 0.5) / N) moved landmarks by tens
of pixels on uncertain joints and lost a person the reference found
(docs/pose_detection.md).  Outside the frame: zero fill (the detector's
letterbox) or edge replication (the landmark crop).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: BlazePose enlarges the region found from its two alignment points by this much.
ROI_SCALE = 1.25


@dataclass(frozen=True)
class Region:
    """A rotated square of the image: ``center`` (x, y) px, ``side`` px, ``rotation`` radians."""

    center: tuple
    side: float
    rotation: float

    def to_image(self, uv: np.ndarray) -> np.ndarray:
        """Image pixels of crop-normalised points ``uv`` (..., 2)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        off = (np.asarray(uv, dtype=float) - 0.5) * self.side
        x = c * off[..., 0] - s * off[..., 1] + self.center[0]
        y = s * off[..., 0] + c * off[..., 1] + self.center[1]
        return np.stack([x, y], axis=-1)


def whole_frame(width: int, height: int) -> Region:
    """The letterboxed whole frame: a square of the long side, centred (the detector's input)."""
    return Region((width / 2.0, height / 2.0), float(max(width, height)), 0.0)


def tiles(width: int, height: int) -> list[Region]:
    """Overlapping squares of half the frame's long side, a half side apart, covering the frame.

    The detector sees the whole frame shrunk to 224 px, where a person a sixth of the frame tall is
    some 30 px and often missed; on these tiles the same person is twice as large (6 tiles for 16:9).
    """
    side = max(width, height) / 2.0
    centres = []
    for extent in (width, height):
        if extent <= side:
            centres.append([extent / 2.0])
        else:
            n = math.ceil((extent - side) / (side / 2.0)) + 1
            centres.append(list(np.linspace(side / 2.0, extent - side / 2.0, n)))
    return [Region((float(x), float(y)), side, 0.0) for y in centres[1] for x in centres[0]]


def region_from_alignment(center_xy, scale_xy, scale: float = ROI_SCALE) -> Region:
    """The region BlazePose derives from its two alignment points (image px).

    The first point is the body's centre (mid-hip), the second lies on the
    circle that encloses the body; the region is the square of twice their
    distance, turned so that the second point is straight above the first,
    enlarged by ``scale``.
    """
    x0, y0 = float(center_xy[0]), float(center_xy[1])
    x1, y1 = float(scale_xy[0]), float(scale_xy[1])
    side = 2.0 * math.hypot(x1 - x0, y1 - y0) * scale
    rotation = math.pi / 2.0 - math.atan2(-(y1 - y0), x1 - x0)
    rotation = (rotation + math.pi) % (2.0 * math.pi) - math.pi
    return Region((x0, y0), side, rotation)


def crop(image: np.ndarray, region: Region, size: int, *, replicate: bool) -> np.ndarray:
    """The ``size`` x ``size`` crop of ``image`` (H, W, C, any dtype) over ``region``, float32 in 0..255.

    Outside the frame: edge pixels (``replicate``) or zeros.  One flat gather per corner: the crop
    runs every frame, as often as the networks.
    """
    h, w = image.shape[:2]
    channels = image.shape[2]
    t = np.arange(size, dtype=np.float64) / size - 0.5
    c, s = math.cos(region.rotation) * region.side, math.sin(region.rotation) * region.side
    x = region.center[0] + c * t[None, :] - s * t[:, None]
    y = region.center[1] + s * t[None, :] + c * t[:, None]
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0).astype(np.float32)[..., None]
    fy = (y - y0).astype(np.float32)[..., None]
    x0 = x0.astype(np.intp)
    y0 = y0.astype(np.intp)
    flat = np.ascontiguousarray(image).reshape(-1, channels)
    out = np.zeros((size, size, channels), dtype=np.float32)
    for dy, wy in ((0, 1.0 - fy), (1, fy)):
        yi = y0 + dy
        yc = np.clip(yi, 0, h - 1)
        for dx, wx in ((0, 1.0 - fx), (1, fx)):
            xi = x0 + dx
            weight = wx * wy
            if not replicate:
                weight = weight * ((xi >= 0) & (xi < w) & (yi >= 0) & (yi < h))[..., None]
            # np.take is several times faster than fancy indexing here; multiply after the cast (mixed types are slow)
            corner = np.take(flat, yc * w + np.clip(xi, 0, w - 1), axis=0).astype(np.float32)
            corner *= weight
            out += corner
    return out
