"""Small footage for the footage-to-animation tests: a real person over a scene filmed by a turning camera.

The person is scikit-image's public-domain ``astronaut`` photo (tests/core/data/person_photos.npz), cut to
the person, which the offline pose detector finds; it walks right in front of a smooth random texture that
the camera pans across (a handheld drift of a few pixels a frame), so Blender's detector finds corners to
follow off the person. ``plain=True`` gives a grey background instead: nothing to follow.
PNG files written with the core's PNG writer, so no bpy is needed to make them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter

ROOT = Path(__file__).resolve().parents[2]
PHOTOS = ROOT / "tests" / "core" / "data" / "person_photos.npz"
W, H = 1280, 540


def camera_path(n: int, seed: int = 3) -> np.ndarray:
    """(n, 2) the background's offset per frame (pixels): a smooth drift, the camera's pan and tilt."""
    rng = np.random.default_rng(seed)
    steps = gaussian_filter(rng.normal(0.0, 3.0, (n + 8, 2)), (2.0, 0.0))[4:n + 4] + np.array([2.5, -1.0])
    return np.cumsum(steps, axis=0) - steps[0]


def person_over_scene(folder: Path, n: int, *, plain: bool = False, seed: int = 3) -> Path:
    """Write ``shot_0001.png`` ... into ``folder``; returns the first (it loads the clip)."""
    from monoskel.core.io.png_plot import encode_png

    folder.mkdir(parents=True, exist_ok=True)
    person = np.load(PHOTOS)["astronaut"][:, 40:360]         # the person, without most of the photo's backdrop
    rng = np.random.default_rng(seed)
    pad = 120
    texture = gaussian_filter(rng.uniform(0, 1, (H + 2 * pad, W + 2 * pad)), 2.5)
    texture = (40 + 180 * (texture - texture.min()) / np.ptp(texture)).astype(np.uint8)
    path = camera_path(n, seed)
    for i in range(n):
        dx, dy = (int(round(v)) for v in path[i])
        if plain:
            frame = np.full((H, W, 3), 128, np.uint8)
        else:
            frame = np.repeat(texture[pad + dy:pad + dy + H, pad + dx:pad + dx + W, None], 3, axis=2)
        ox = 460 + 3 * i - dx                   # walks right, 3 px a frame, where the camera sees the scene
        frame[H - 512:, ox:ox + person.shape[1]] = person
        (folder / f"shot_{i + 1:04d}.png").write_bytes(encode_png(frame, level=1))
    return folder / "shot_0001.png"
