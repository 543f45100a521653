"""Make the README's picture: frames of a clip with the detected joints and the solved skeleton on them.

The clip is the footage tests' own (``tests/blender/person_footage.py``: a public-domain photo of a person
moving over a textured scene that a handheld camera pans across). The picture is made the way a user's
review page is: ``batch.py --video`` detects the joints, follows the background, estimates and builds; then
three frames of the footage are drawn with the review page's own drawing
(:func:`core.review.footage_sheet.draw_frame`) and set side by side.

    python tools/readme_picture.py [--out docs/images/footage_with_skeleton.png]

Needs the Blender environment of ``make demo`` (``.venvs/bpy-5.0.1/bin/python``): Blender decodes the
footage and builds the scene, as it does for a user.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FRAMES = 24
TILE_WIDTH = 400


def decoded_frames(first_png: Path, count: int) -> list[np.ndarray]:
    """(H, W, 3) uint8 of ``count`` numbered PNG frames, decoded by Blender as the review page's are."""
    import bpy

    out = []
    for i in range(count):
        path = first_png.with_name(f"shot_{i + 1:04d}.png")
        image = bpy.data.images.load(str(path))
        w, h = image.size
        px = np.empty(w * h * 4, dtype=np.float32)
        image.pixels.foreach_get(px)
        bpy.data.images.remove(image)
        rgb = px.reshape(h, w, 4)[::-1, :, :3]              # Blender's rows run bottom-up
        out.append(np.clip(np.round(rgb * 255), 0, 255).astype(np.uint8))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "images" / "footage_with_skeleton.png"))
    args = parser.parse_args()

    import extension_loader

    extension_loader.load_extension()
    from monoskel.core.io.png_plot import encode_png
    from monoskel.core.result import read_estimate_json
    from monoskel.core.review.footage_sheet import draw_frame
    from monoskel.core.review.residuals import reprojected_pixels
    from monoskel.core.tracks import read_tracks_json
    from tests.blender.person_footage import person_over_scene

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        first = person_over_scene(tmp / "clip", FRAMES)
        result, tracks_path = tmp / "result.json", tmp / "tracks.json"
        run = subprocess.run([sys.executable, str(ROOT / "batch.py"), "--video", str(first), "--output",
                              str(tmp / "scene.blend"), "--result", str(result), "--tracks-out", str(tracks_path),
                              "--no-report"], capture_output=True, text=True)
        if run.returncode != 0:
            print(run.stderr.strip().splitlines()[-1] if run.stderr.strip() else "batch.py failed", file=sys.stderr)
            return 1
        est, tracks = read_estimate_json(str(result)), read_tracks_json(str(tracks_path))
        frames = decoded_frames(first, FRAMES)
        reproj = reprojected_pixels(est, tracks.image_size)
        picks = [0, FRAMES // 2, FRAMES - 1]
        tiles = [draw_frame(frames[i], tracks.xy[i], tracks.present[i], reproj[i], width=TILE_WIDTH) for i in picks]
        gap = np.full((tiles[0].shape[0], 6, 3), 255, np.uint8)
        sheet = np.concatenate([t for tile in tiles for t in (tile, gap)][:-1], axis=1)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_bytes(encode_png(sheet, level=9))
    print(f"wrote {out} ({sheet.shape[1]} x {sheet.shape[0]} px)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
