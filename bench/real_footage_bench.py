"""The pose detector on real footage with no ground truth: what can be measured.

    python bench/real_footage_bench.py VIDEO [--reference] [--handheld] [--json OUT.json]

Default VIDEO: OpenCV's sample ``vtest.avi`` (Debian's ``opencv-doc`` package puts it under
/usr/share/doc/opencv-doc/examples/data/; 768 x 576, 10 frames/s, 79.5 s: people walking across a
campus square, seen from a first floor, crossing, leaving and entering).  It is read, never copied
into the repository (docs/pose_detection.md says why).

Rows: speed and the found share in both modes; the detector's own errors from the tracking run
(:func:`core.pose_detection.quality.track_quality`: jitter on still spells, left/right flips,
drop-outs, person switches); with ``--reference`` and MediaPipe installed, our landmarks against
MediaPipe's own video-mode run (torso joints where both found someone, and how often the two follow
different people); with ``--handheld``, the clip re-framed by a virtual handheld operator (pans,
zoom, shake over the real pixels) and detected again; the estimate of the longest stretch of one
person, its warnings, and its bone proportions against adult anthropometric ratios that hold for
a detector's landmarks (segment lengths over standing height, Drillis and Contini 1966, as
tabulated in Winter's *Biomechanics and Motor Control of Human Movement*).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

DEFAULT_VIDEO = "/usr/share/doc/opencv-doc/examples/data/vtest.avi"
#: segment length / standing height (Drillis & Contini): hip joint to knee, knee to ankle, shoulder to
#: elbow, elbow to wrist, hip joint height minus shoulder height (the trunk between the landmarks).
DRILLIS_CONTINI = {"thigh": 0.245, "shank": 0.246, "upper_arm": 0.186, "forearm": 0.146, "trunk": 0.818 - 0.530}
TORSO_JOINTS = ("l_shoulder", "r_shoulder", "l_hip", "r_hip")
#: Two tracks follow the same person in a frame when their torso joints lie within this (median, px).
SAME_PERSON_PX = 40.0


def torso_gaps(xy_a, xy_b):
    """(found in a, found in b, found in both, (both, 4) torso joint distances px) of two (F, 17, 2) tracks."""
    from core.skeleton import JOINT_INDEX

    idx = [JOINT_INDEX[name] for name in TORSO_JOINTS]
    a = np.isfinite(xy_a[:, idx, 0]).all(1)
    b = np.isfinite(xy_b[:, idx, 0]).all(1)
    both = a & b
    return a, b, both, np.linalg.norm(xy_a[both][:, idx] - xy_b[both][:, idx], axis=-1)


def detect(video, mode):
    from core.pose_detection.detect import detect_frames
    from core.pose_detection.frames import open_frames

    source = open_frames(video)
    t0 = time.perf_counter()
    result = detect_frames(source.frames(0), fps=source.fps, image_size=(source.width, source.height), mode=mode,
                           total=source.count, source=video)
    return result, time.perf_counter() - t0


def handheld_run(video, still_tracks, seed=0):
    """The clip re-framed by a virtual handheld operator: a 16:9 window (half the frame wide, zooming
    0.8-1.25x) that pans and shakes over the real pixels, scaled to 1280 x 720.  Our detection on it is
    mapped back to the clip and compared with the still camera's run where both follow the same person."""
    from core.pose_detection.detect import detect_frames
    from core.pose_detection.frames import open_frames

    source = open_frames(video)
    w, h = source.width, source.height
    n = source.count
    rng = np.random.default_rng(seed)
    t = np.arange(n) / source.fps

    def wander(amplitude, periods):
        return sum(amplitude * rng.uniform(0.3, 1.0) * np.sin(2 * np.pi * t / p + rng.uniform(0, 2 * np.pi))
                   for p in periods)
    zoom = np.exp(wander(0.08, (7.0, 3.1)))                         # window side over the base, about 0.8-1.25
    base_w = w / 2.0
    cx = w / 2 + wander(w / 6, (11.0, 4.3)) + rng.normal(0, 1.5, n)   # pans plus hand shake
    cy = h / 2 + wander(h / 10, (9.0, 2.7)) + rng.normal(0, 1.5, n)
    out_w, out_h = 1280, 720

    def frames():
        for i, frame in enumerate(source.frames(0)):
            ww = base_w * zoom[i]
            wh = ww * out_h / out_w
            x0 = np.clip(cx[i] - ww / 2, 0, w - ww)
            y0 = np.clip(cy[i] - wh / 2, 0, h - wh)
            xs = x0 + (np.arange(out_w) + 0.5) * ww / out_w - 0.5
            ys = y0 + (np.arange(out_h) + 0.5) * wh / out_h - 0.5
            xi, yi = np.clip(xs.astype(int), 0, w - 2), np.clip(ys.astype(int), 0, h - 2)
            fx, fy = (xs - xi)[None, :, None], (ys - yi)[:, None, None]
            img = frame[..., :3].astype(np.float32)
            a = img[yi][:, xi] * (1 - fx) + img[yi][:, xi + 1] * fx
            b = img[yi + 1][:, xi] * (1 - fx) + img[yi + 1][:, xi + 1] * fx
            windows.append((x0, y0, ww / out_w))
            yield (a * (1 - fy) + b * fy).astype(np.uint8)

    windows = []
    result = detect_frames(frames(), fps=source.fps, image_size=(out_w, out_h), total=n, source=video)
    sec = result.seconds                                             # the detection alone, not the re-framing
    x0, y0, k = (np.array(v)[:, None, None] for v in zip(*windows))
    back = np.stack([result.tracks.xy[..., 0] * k[..., 0] + x0[..., 0], result.tracks.xy[..., 1] * k[..., 0]
                     + y0[..., 0]], axis=-1)
    a, _, _, gaps = torso_gaps(back, still_tracks.xy)
    d = np.median(gaps, axis=1)
    same = d <= SAME_PERSON_PX
    return {"frames_per_s": n / sec, "found_share": float(a.mean()), "same_person_share": float(same.mean()),
            "torso_px_median_same_person": float(np.median(d[same])) if same.any() else None,
            "pan_range_px": float(np.ptp(cx)), "zoom_range": [float(zoom.min()), float(zoom.max())]}


def reference_tracks(video, fps, size):
    """MediaPipe's own BlazePose (video mode, full model, no landmark smoothing) on the same frames."""
    try:
        import mediapipe as mp
    except ImportError:
        return None
    from core.io.formats.mediapipe import landmarks_to_tracks
    from core.pose_detection.frames import open_frames

    xy, vis = [], []
    with mp.solutions.pose.Pose(static_image_mode=False, model_complexity=1, smooth_landmarks=False) as pose:
        for frame in open_frames(video).frames(0):
            r = pose.process(np.ascontiguousarray(frame[..., :3]))
            if r.pose_landmarks is None:
                xy.append(np.full((33, 2), np.nan))
                vis.append(np.zeros(33))
            else:
                xy.append([[lm.x, lm.y] for lm in r.pose_landmarks.landmark])
                vis.append([lm.visibility for lm in r.pose_landmarks.landmark])
    return landmarks_to_tracks(np.array(xy, float), np.array(vis, float), fps=fps, image_size=size,
                               source="mediapipe", meta={})


def compare(ours, ref):
    a, b, both, d = torso_gaps(ours.xy, ref.xy)
    per_frame = np.median(d, axis=1)
    same = per_frame <= SAME_PERSON_PX
    return {"ours_found": float(a.mean()), "reference_found": float(b.mean()), "both": int(both.sum()),
            "different_person_share": float(1 - same.mean()) if both.any() else None,
            "torso_px_median_same_person": float(np.median(d[same])) if same.any() else None,
            "torso_px_p90_same_person": float(np.percentile(d[same], 90)) if same.any() else None,
            "torso_px_median_all": float(np.median(per_frame)) if both.any() else None}


def estimate_stretch(tracks, quality):
    from core.estimate import estimate
    from core.skeleton import CLASSES

    s = quality["longest_stretch"]
    part = tracks.replaced(xy=tracks.xy[s["start"]:s["start"] + s["frames"]],
                           conf=tracks.conf[s["start"]:s["start"] + s["frames"]])
    est = estimate(part)
    shares = np.array([est.proportions[c] for c in CLASSES])
    lengths = dict(zip(CLASSES, shares))
    lengths["trunk"] = lengths["lower_spine"] + lengths["upper_spine"]
    # scale-free: each ratio over the leg (thigh + shank), the table's the same way
    leg = lengths["thigh"] + lengths["shank"]
    table_leg = DRILLIS_CONTINI["thigh"] + DRILLIS_CONTINI["shank"]
    ratios = {k: float((lengths[k] / leg) / (v / table_leg) - 1.0) for k, v in DRILLIS_CONTINI.items()}
    return {"frames": [s["start"], s["start"] + s["frames"] - 1], "warnings": est.diagnostics.get("warnings", []),
            "off_table": ratios, "height_m": est.height_m}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("video", nargs="?", default=DEFAULT_VIDEO)
    p.add_argument("--reference", action="store_true", help="compare with MediaPipe's own run (needs mediapipe)")
    p.add_argument("--handheld", action="store_true",
                   help="also re-frame the clip by a virtual handheld operator and detect on that")
    p.add_argument("--json", help="write every figure here")
    args = p.parse_args()
    if not os.path.exists(args.video):
        print(f"{args.video} not found (apt-get install opencv-doc brings the default clip)")
        return 2
    from core.pose_detection.quality import track_quality

    out = {"video": args.video, "cores": os.cpu_count()}
    print(f"{args.video}; {os.cpu_count()} cores")
    print("| mode | frames | seconds | frames/s | person found | detector runs |")
    print("|---|---|---|---|---|---|")
    runs = {}
    for mode in ("tracking", "per-frame"):
        result, sec = detect(args.video, mode)
        runs[mode] = result
        n = len(result.frame_numbers)
        found, runs_ = result.found_share, result.detector_runs
        print(f"| {mode} | {n} | {sec:.1f} | {n / sec:.1f} | {100 * found:.0f} % | {runs_} |")
        out[mode] = {"frames": n, "seconds": sec, "found_share": found, "detector_runs": runs_}
    tracks = runs["tracking"].tracks
    q = track_quality(tracks)
    out["quality"] = q
    print(f"\nperson switches: {q['person_switches']} (frames {q['switch_frames']}); longest stretch of one person "
          f"{q['longest_stretch']['seconds']:.1f} s from frame {q['longest_stretch']['start']}; "
          f"{q['still_frames']} still frame pairs; torso {q['torso_px']:.0f} px (median)")
    print("\n| joint | jitter median px (torso lengths) | p95 px | dropped share | longest drop-out s |")
    print("|---|---|---|---|---|")
    for name, drop in q["dropouts"].items():
        j = q["jitter"].get(name)
        jit = f"{j['median_px']:.2f} ({j['median_torso']:.3f}) | {j['p95_px']:.2f}" if j else "- | -"
        print(f"| {name} | {jit} | {100 * drop['share']:.1f} % | {drop['longest_s']:.1f} |")
    print("\n| pair | left/right flips | frame pairs | rate |")
    print("|---|---|---|---|")
    for name, s in q["swaps"].items():
        print(f"| {name} | {s['flips']} | {s['pairs']} | {100 * s['rate']:.1f} % |")
    if args.reference:
        ref = reference_tracks(args.video, tracks.fps, tracks.image_size)
        if ref is None:
            print("\n(--reference needs mediapipe installed)")
        else:
            c = compare(tracks, ref)
            out["reference"] = c
            print("\nagainst MediaPipe's own run:", json.dumps({k: round(v, 3) if isinstance(v, float) else v
                                                               for k, v in c.items()}))
    if args.handheld:
        hh = handheld_run(args.video, tracks)
        out["handheld"] = hh
        print("\nvirtual handheld operator over the real pixels (1280 x 720):",
              json.dumps({k: [round(x, 2) for x in v] if isinstance(v, list) else round(v, 3) if v else v
                          for k, v in hh.items()}))
    e = estimate_stretch(tracks, q)
    out["estimate"] = e
    print(f"\nestimate of frames {e['frames'][0]}-{e['frames'][1]}: off the adult table (per leg length): "
          + ", ".join(f"{k} {100 * v:+.0f} %" for k, v in e["off_table"].items()))
    for w in e["warnings"]:
        print(f"  warning: {w}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
