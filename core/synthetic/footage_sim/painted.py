"""Footage painted with numpy: textured patches moving along known image paths.

Refining joint tracks on the footage (:mod:`core.track_refinement`) is measured on images whose truth
is known: each joint is a patch of its own smooth random texture, drawn at the joint's true image
position (sub-pixel, bilinear), turning slowly as the figure moves, on a dim noisy background. Image
rows are top-down, pixels grey levels 0-255; a pixel's centre is at integer coordinates, as the core's
tracks are.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter, map_coordinates

from ...io import png_plot


def patch_textures(n: int, size: int, seed: int = 0) -> np.ndarray:
    """(n, size, size) textures in 0-1: smoothed noise, each stretched to the full range."""
    rng = np.random.default_rng(seed)
    tex = gaussian_filter(rng.uniform(0.0, 1.0, (n, size, size)), (0, 1.2, 1.2))
    lo = tex.min(axis=(1, 2), keepdims=True)
    hi = tex.max(axis=(1, 2), keepdims=True)
    return (tex - lo) / np.maximum(hi - lo, 1e-9)


def paint_frames(paths: np.ndarray, image_size: tuple[int, int], *, patch_px: int = 17, turn_deg_per_frame: float = 1.0,
                 noise: float = 2.0, seed: int = 0, zoom: np.ndarray | None = None) -> np.ndarray:
    """(n, H, W) uint8 frames with one textured patch per path: ``paths`` (n, k, 2) pixels, NaN = not drawn.

    Later paths are drawn over earlier ones where they overlap (as a nearer limb hides a farther one).
    ``zoom`` (n,), each frame's focal length over the first's, scales every patch as a zoom scales what
    it films (a patch's corner then moves as a point of the scene does); None keeps their size.
    """
    paths = np.asarray(paths, dtype=float)
    n, k = paths.shape[:2]
    width, height = (int(v) for v in image_size)
    rng = np.random.default_rng(seed + 1)
    tex = patch_textures(k, patch_px + 6, seed)
    scales = np.ones(n) if zoom is None else np.asarray(zoom, dtype=float)
    frames = np.empty((n, height, width), dtype=np.uint8)
    for i in range(n):
        half = patch_px * scales[i] / 2.0
        yy, xx = np.mgrid[-int(half) - 2:int(half) + 3, -int(half) - 2:int(half) + 3].astype(float)
        img = 60.0 + rng.normal(0.0, noise, (height, width))
        for j in range(k):
            cx, cy = paths[i, j]
            if not (np.isfinite(cx) and np.isfinite(cy)):
                continue
            angle = np.radians(turn_deg_per_frame * i + 37.0 * j)
            c, s = np.cos(angle), np.sin(angle)
            x0, y0 = int(round(cx)), int(round(cy))
            px, py = xx + x0, yy + y0                       # image pixels around the patch
            u, v = px - cx, py - cy                         # offsets from the patch centre
            tu, tv = c * u + s * v, -s * u + c * v          # into the patch's own (turned) axes
            inside = (np.abs(tu) <= half) & (np.abs(tv) <= half) & (px >= 0) & (px < width) & (py >= 0) & (py < height)
            if not inside.any():
                continue
            centre = (patch_px + 6 - 1) / 2.0
            vals = map_coordinates(tex[j], [tv[inside] / scales[i] + centre, tu[inside] / scales[i] + centre], order=1)
            shade = 40.0 + 180.0 * vals + rng.normal(0.0, noise, vals.shape)
            img[py[inside].astype(int), px[inside].astype(int)] = shade
        frames[i] = np.clip(np.round(img), 0, 255).astype(np.uint8)
    return frames


def write_png_sequence(frames: np.ndarray, directory, stem: str = "frame") -> list:
    """Write ``frames`` (n, H, W) uint8 as ``stem_0001.png`` ...; returns the paths (first one loads the clip)."""
    from pathlib import Path

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, frame in enumerate(frames):
        path = directory / f"{stem}_{i + 1:04d}.png"
        path.write_bytes(png_plot.encode_png(np.repeat(frame[:, :, None], 3, axis=2), level=1))
        paths.append(path)
    return paths
