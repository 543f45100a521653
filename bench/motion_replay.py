"""Tune the motion cleanup offline: replay saved raw solves with settings variants (tune half only).

``bench/motion_bench.py --save DIR --cleanup off`` keeps each raw joint solve with its truth; this
applies :func:`core.motion_cleanup.clean_motion` to them with each variant below and prints the
median measures per variant and scenario, at no solve cost.  It is the shipped path
(:func:`core.estimate.estimate` cleans the finished estimate at the clip's frame rate), so a variant
here is what the bench would measure with it.

    python bench/motion_replay.py /tmp/motion_tune
"""

from __future__ import annotations

import dataclasses
import glob
import json
import os
import sys
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.motion_bench import KEYS, _fmt  # noqa: E402
from core.evaluation import metrics  # noqa: E402
from core.motion_cleanup import DEFAULT_CLEANUP, clean_motion  # noqa: E402


def variants() -> dict:
    d = DEFAULT_CLEANUP
    c = d.contacts
    return {
        "raw": None,
        "default": d,
        "clip low level": dataclasses.replace(d, contacts=dataclasses.replace(c, low_level="clip", on_height=0.04,
                                                                                off_height=0.07)),
        "low window 1.5 s": dataclasses.replace(d, contacts=dataclasses.replace(c, low_level="clip", low_window_s=1.5)),
        "low window 3 s": dataclasses.replace(d, contacts=dataclasses.replace(c, low_level="clip", low_window_s=3.0)),
    }


def scores(z, joints) -> dict:
    from bench.motion_bench import motion_scores

    fps = float(z["fps"])
    stance = [{0: "l", 1: "r"}.get(int(s)) for s in z["truth_stance"]]
    truth = SimpleNamespace(joints_3d=z["truth_joints"], stance=stance, n_frames=len(stance), fps=fps,
                            rotvec_deg=z["truth_rotvec_deg"] if "truth_rotvec_deg" in z.files else None)
    tracks = SimpleNamespace(xy=z["xy"], image_size=tuple(z["image_size"]))
    return motion_scores(joints, z["rotvec_deg"], z["focal_mm"], tracks, truth)


def main(argv=None) -> int:
    folder = (argv or sys.argv[1:])[0]
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "*.npz"))):
        z = np.load(path)
        case = json.loads(str(z["case"]))
        for name, st in variants().items():
            j = z["joints"] if st is None else clean_motion(z["joints"], z["world_from_cam0"], float(z["fps"]),
                                                            float(z["height_m"]), st)[0]
            rows.append({"scenario": case["scenario"], "variant": name, **scores(z, j)})
    keys = [k for k in KEYS if k[0] != "seconds"]
    print("| scenario | variant | cases | " + " | ".join(h for _, h, _ in keys) + " |")
    print("|---" * (3 + len(keys)) + "|")
    for s in dict.fromkeys(r["scenario"] for r in rows):
        for v in variants():
            rs = [r for r in rows if r["scenario"] == s and r["variant"] == v]
            med = [_fmt(float(np.nanmedian([r[k] for r in rs])), spec) for k, _, spec in keys]
            exc = np.nanmedian([abs(r["planted_excess_mm_s"]) for r in rs])
            print(f"| {s} | {v} | {len(rs)} | " + " | ".join(med) + f" | abs excess {exc:.0f} |")
    _ = metrics
    return 0


if __name__ == "__main__":
    sys.exit(main())
