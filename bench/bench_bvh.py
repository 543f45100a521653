"""Benchmark: read + forward kinematics of a long BVH clip (target: well under a second).

Writes a synthetic 10,000-frame, 31-joint humanoid BVH (CMU-like tree, 6 root
channels, 3 rotation channels elsewhere = 96 channels) to /tmp and times
``read_bvh``, ``Bvh.world_positions`` (all frames at once), the canonical
mapping and the whole rigid figure (``motion_from_bvh_file``).

Run from the repository root: ``python bench/bench_bvh.py [--frames N] [--repeat R]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from core.io.bvh import read_bvh  # noqa: E402
from core.io.bvh_mapping import build_mapping  # noqa: E402
from core.synthetic.rigid_figure import motion_from_bvh_file  # noqa: E402

# (name, parent, offset) of a 31-joint CMU-like humanoid (cm-ish units).
_TREE = [
    ("Hips", None, (0, 0, 0)),
    ("LHipJoint", "Hips", (0, 0, 0)), ("LeftUpLeg", "LHipJoint", (9, -8, 2)), ("LeftLeg", "LeftUpLeg", (0, -42, 0)),
    ("LeftFoot", "LeftLeg", (0, -41, 0)), ("LeftToeBase", "LeftFoot", (0, -4, 12)),
    ("RHipJoint", "Hips", (0, 0, 0)), ("RightUpLeg", "RHipJoint", (-9, -8, 2)), ("RightLeg", "RightUpLeg", (0, -42, 0)),
    ("RightFoot", "RightLeg", (0, -41, 0)), ("RightToeBase", "RightFoot", (0, -4, 12)),
    ("LowerBack", "Hips", (0, 0, 0)), ("Spine", "LowerBack", (0, 12, 0)), ("Spine1", "Spine", (0, 13, 0)),
    ("Neck", "Spine1", (0, 0, 0)), ("Neck1", "Neck", (0, 9, 0)), ("Head", "Neck1", (0, 9, 0)),
    ("LeftShoulder", "Spine1", (0, 0, 0)), ("LeftArm", "LeftShoulder", (17, 6, 0)),
    ("LeftForeArm", "LeftArm", (28, 0, 0)), ("LeftHand", "LeftForeArm", (25, 0, 0)),
    ("LeftFingerBase", "LeftHand", (0, 0, 0)), ("LFingers", "LeftFingerBase", (4, 0, 0)),
    ("LThumb", "LeftHand", (0, 0, 0)),
    ("RightShoulder", "Spine1", (0, 0, 0)), ("RightArm", "RightShoulder", (-17, 6, 0)),
    ("RightForeArm", "RightArm", (-28, 0, 0)), ("RightHand", "RightForeArm", (-25, 0, 0)),
    ("RightFingerBase", "RightHand", (0, 0, 0)), ("RFingers", "RightFingerBase", (-4, 0, 0)),
    ("RThumb", "RightHand", (0, 0, 0)),
]
_END = {"LeftToeBase": (0, 0, 6), "RightToeBase": (0, 0, 6), "Head": (0, 10, 0), "LFingers": (3, 0, 0),
        "LThumb": (3, 0, 3), "RFingers": (-3, 0, 0), "RThumb": (-3, 0, 3)}


def synthetic_bvh_text(n_frames: int, seed: int = 0) -> str:
    """A 31-joint BVH text with smooth random motion."""
    children: dict[str, list[str]] = {}
    for name, parent, _ in _TREE:
        children.setdefault(parent, []).append(name)
    offsets = {name: off for name, _, off in _TREE}
    lines = ["HIERARCHY"]

    def emit(name: str, depth: int) -> None:
        pad = "\t" * depth
        lines.append(f"{pad}{'ROOT' if depth == 0 else 'JOINT'} {name}")
        lines.append(pad + "{")
        lines.append(f"{pad}\tOFFSET {offsets[name][0]:.5f} {offsets[name][1]:.5f} {offsets[name][2]:.5f}")
        if depth == 0:
            lines.append(f"{pad}\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation")
        else:
            lines.append(f"{pad}\tCHANNELS 3 Zrotation Yrotation Xrotation")
        for child in children.get(name, []):
            emit(child, depth + 1)
        if name in _END:
            e = _END[name]
            lines.extend([f"{pad}\tEnd Site", pad + "\t{", f"{pad}\t\tOFFSET {e[0]} {e[1]} {e[2]}", pad + "\t}"])
        lines.append(pad + "}")

    emit("Hips", 0)
    n_channels = 6 + 3 * (len(_TREE) - 1)
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames)[:, None] / 120.0
    freq = rng.uniform(0.2, 2.0, n_channels)
    phase = rng.uniform(0, 2 * np.pi, n_channels)
    data = 30.0 * np.sin(2 * np.pi * freq * t + phase)
    data[:, 0] = 100.0 * t[:, 0]
    data[:, 1] = 95.0 + 3.0 * np.sin(2 * np.pi * 2 * t[:, 0])
    lines += ["MOTION", f"Frames: {n_frames}", "Frame Time: 0.00833333"]
    body = "\n".join(" ".join(f"{v:.5f}" for v in row) for row in data)
    return "\n".join(lines) + "\n" + body + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--path", default="/tmp/monoskel_bench_10k.bvh")
    args = parser.parse_args(argv)
    with open(args.path, "w") as handle:
        handle.write(synthetic_bvh_text(args.frames))
    size_mb = os.path.getsize(args.path) / 1e6
    bvh = read_bvh(args.path)
    print(f"file {args.path}: {bvh.n_frames} frames, {sum(1 for e in bvh.is_end_site if not e)} joints "
          f"(+{int(bvh.is_end_site.sum())} End Sites), {bvh.motion.shape[1]} channels, {size_mb:.1f} MB")
    stages = ("read_bvh", "world_positions", "read+fk", "mapping", "motion_from_bvh_file")
    wall: dict[str, list[float]] = {name: [] for name in stages}
    cpu: dict[str, list[float]] = {name: [] for name in stages}
    for _ in range(args.repeat):
        marks = [(time.perf_counter(), time.process_time())]
        bvh = read_bvh(args.path)
        marks.append((time.perf_counter(), time.process_time()))
        positions = bvh.world_positions()
        marks.append((time.perf_counter(), time.process_time()))
        build_mapping(bvh)
        marks.append((time.perf_counter(), time.process_time()))
        motion_from_bvh_file(args.path)
        marks.append((time.perf_counter(), time.process_time()))
        spans = {"read_bvh": (0, 1), "world_positions": (1, 2), "read+fk": (0, 2), "mapping": (2, 3),
                 "motion_from_bvh_file": (3, 4)}
        for name, (a, b) in spans.items():
            wall[name].append(marks[b][0] - marks[a][0])
            cpu[name].append(marks[b][1] - marks[a][1])
    assert positions.shape == (args.frames, bvh.n_joints, 3)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; CPU time is this process only")
    for name in stages:
        print(f"{name:>22}: wall best {min(wall[name]) * 1000:7.1f} ms, median {np.median(wall[name]) * 1000:7.1f} ms"
              f" | CPU best {min(cpu[name]) * 1000:7.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
