"""Speed of the offline pose detector at 1280 x 720: the core on frames in memory, and Blender end to end.

    python bench/detect_bench.py [--frames 900] [--no-blender]

The footage is a real photo (scikit-image's public-domain ``astronaut``, as in the tests) moving
across a 1280 x 720 frame.  Rows:

* core, tracking / per-frame: ``detect_frames`` on frames made in memory (making them is not
  counted); start-up (loading both networks) is timed apart and included in the total;
* Blender, mp4: the Blender path as ``batch.py --video`` runs it: Blender renders the frames into
  an H.264 mp4 first (not timed), then loading the clip, decoding it through the sequencer, the
  detector and writing the joint markers are timed together.  Needs the ``bpy`` module.

With ``--reference``, and MediaPipe installed, it also compares our landmarks with MediaPipe's own
run on the two test photos and on them padded to 720 x 560, 1280 x 720 and 512 x 900.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

PHOTOS = os.path.join(ROOT, "tests", "core", "data", "person_photos.npz")
W, H = 1280, 720


def photo(name="astronaut"):
    img = np.load(PHOTOS)[name]
    return np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img


def frame_at(img, i, n):
    """The photo on frame ``i`` of ``n``: it moves across and back, border replicated."""
    t = 0.5 - 0.5 * np.cos(2 * np.pi * i / max(1, n - 1))
    ox, oy = int(40 + t * (W - 512 - 80)), int(20 + t * (H - 512 - 40))
    return np.pad(img, ((oy, H - 512 - oy), (ox, W - 512 - ox), (0, 0)), mode="edge")


def core_rows(n):
    from core.pose_detection.detect import DetectionRun
    from core.pose_detection.runtime import Networks

    img = photo()
    for mode in ("tracking", "per-frame"):
        t0 = time.perf_counter()
        networks = Networks()
        startup = time.perf_counter() - t0
        run = DetectionRun(fps=30.0, networks=networks, mode=mode)
        for i in range(n):
            run.add(frame_at(img, i, n), i)
        result = run.finish()
        total = startup + result.seconds
        print(f"| core, {mode} | {n} | {startup:.2f} | {total:.1f} | {n / total:.1f} | {result.detector_runs} | "
              f"{100 * result.found_share:.0f} % |")


def blender_row(n):
    import bpy

    sys.path.insert(0, ROOT)
    import extension_loader

    extension_loader.load_extension()
    from monoskel.blender.compat import sequencer_strips, set_output_format
    from monoskel.blender.pose_detection.clip_detect import detect_clip, load_clip

    bpy.ops.wm.read_factory_settings(use_empty=True)
    img = photo()
    with tempfile.TemporaryDirectory() as tmp:
        still = bpy.data.images.new("frame", W, H)
        still.file_format = "PNG"
        paths = []
        for k in range(12):  # twelve stills, each held for a stretch: a moving shot in steps
            rgba = np.concatenate([frame_at(img, k * n // 12, n)[::-1].astype(np.float32) / 255,
                                   np.ones((H, W, 1), np.float32)], axis=2)
            still.pixels.foreach_set(rgba.ravel())
            still.filepath_raw = os.path.join(tmp, f"s_{k + 1:04d}.png")
            still.save()
            paths.append(os.path.basename(still.filepath_raw))
        scene = bpy.data.scenes.new("encode")
        editor = scene.sequence_editor_create()
        strip = sequencer_strips(editor).new_image(name="im", filepath=os.path.join(tmp, paths[0]), channel=1,
                                                   frame_start=1)
        for i in range(1, n):  # each still held for n / 12 frames: a moving shot in steps
            strip.elements.append(paths[i * len(paths) // n])
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
        scene.frame_start, scene.frame_end, scene.render.fps = 1, n, 30
        set_output_format(scene.render.image_settings, "FFMPEG")
        scene.render.ffmpeg.format, scene.render.ffmpeg.codec = "MPEG4", "H264"
        scene.view_settings.view_transform = "Standard"
        scene.render.use_sequencer = True
        scene.render.filepath = os.path.join(tmp, "clip.mp4")
        with bpy.context.temp_override(scene=scene):
            bpy.ops.render.render(animation=True, scene=scene.name)
        bpy.data.scenes.remove(scene)
        video = next(os.path.join(tmp, f) for f in os.listdir(tmp) if f.endswith(".mp4"))
        t0 = time.perf_counter()
        clip = load_clip(video)
        result = detect_clip(clip)
        total = time.perf_counter() - t0
        frames = len(result.frame_numbers)
        print(f"| Blender {bpy.app.version_string}, mp4 decode + detect + markers, tracking | {frames} | - | "
              f"{total:.1f} | {frames / total:.1f} | {result.detector_runs} | {100 * result.found_share:.0f} % |")
        jitter_rows(result.tracks, n, len(paths))


def jitter_rows(tracks, n, stills):
    """Frame-to-frame motion of each joint while the picture holds still (H.264 noise + tracking feedback)."""
    from monoskel.core.skeleton import JOINTS

    still = np.array([i * stills // n for i in range(n)])
    same = still[1:] == still[:-1]
    step = np.linalg.norm(np.diff(tracks.xy, axis=0), axis=-1)[same]
    seen = (tracks.conf[1:] > 0.5) & (tracks.conf[:-1] > 0.5)
    seen = seen[same]
    print("\njitter on still spells (px, frame to frame, joints seen with confidence > 0.5):")
    print("| joint | median | 95th percentile | frames |")
    print("|---|---|---|---|")
    for j, name in enumerate(JOINTS):
        d = step[seen[:, j], j]
        if d.size:
            print(f"| {name} | {np.median(d):.2f} | {np.percentile(d, 95):.2f} | {d.size} |")


def reference_rows():
    try:
        import mediapipe as mp
    except ImportError:
        print("(--reference needs mediapipe installed)")
        return
    from core.pose_detection.runtime import Networks
    from core.pose_detection.tracker import PoseTracker

    networks = Networks()
    print("| photo | frame | median over 33 px | torso (nose, shoulders, hips) px | visibility max diff |")
    print("|---|---|---|---|---|")
    for name in ("astronaut", "camera"):
        img = photo(name)
        for ox, oy, w, h in ((0, 0, 512, 512), (40, 30, 720, 560), (300, 100, 1280, 720), (0, 0, 512, 900)):
            fr = np.pad(img, ((oy, h - 512 - oy), (ox, w - 512 - ox), (0, 0)), mode="edge")
            with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1) as pose:
                r = pose.process(fr)
            ours = PoseTracker(networks, "per-frame").process(fr)
            if r.pose_landmarks is None:
                print(f"| {name} | {w}x{h} | neither finds a person: {not np.isfinite(ours.xy[0, 0])} | | |")
                continue
            ref = np.array([[lm.x * w, lm.y * h] for lm in r.pose_landmarks.landmark])
            vis = np.array([lm.visibility for lm in r.pose_landmarks.landmark])
            d = np.hypot(*(ours.xy - ref).T)
            torso = ", ".join(f"{v:.1f}" for v in d[[0, 11, 12, 23, 24]])
            print(f"| {name} | {w}x{h} | {np.median(d):.1f} | {torso} | {np.abs(ours.visibility - vis).max():.3f} |")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=900)
    p.add_argument("--no-blender", action="store_true")
    p.add_argument("--reference", action="store_true", help="compare with MediaPipe's own run (needs mediapipe)")
    args = p.parse_args()
    if args.reference:
        reference_rows()
        return 0
    print(f"host: {os.cpu_count()} cores; 1280 x 720 frames")
    print("| path | frames | start-up s | total s | frames/s | detector runs | person found |")
    print("|---|---|---|---|---|---|---|")
    core_rows(args.frames)
    if not args.no_blender:
        try:
            import bpy  # noqa: F401
        except ImportError:
            print("(no bpy: Blender row skipped)")
        else:
            blender_row(args.frames)
    return 0


if __name__ == "__main__":
    sys.exit(main())
