"""Speed of building a 10,000-frame result against Blender's own BVH importer, in one run.

The clip is the built-in walk sampled at 10,000 frames, filmed by the
paper's virtual camera; its ground truth is built as the "estimate".  Timed:

* ours: ``build_all`` (16-bone armature with root translation and quaternion
  keys, camera with keyed rotation and focal length, 17 track markers, the
  diagnostics properties), and for reference the armature and camera alone;
* Blender: ``bpy.ops.import_anim.bvh`` loading the same motion (our armature
  exported to BVH with Blender's exporter first, untimed) into an armature.

Run:  python bench/bench_blender_build.py [--frames 10000]
(with any Python that has the PyPI ``bpy`` module, or
``blender -b --python bench/bench_blender_build.py -- --frames 10000``).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=10_000)
    return p.parse_args(argv)


def main() -> int:
    args = _args()
    sys.path.insert(0, ROOT)
    import bpy

    import extension_loader

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = extension_loader.load_extension()
    addon.register()
    from monoskel.blender import build, export
    from monoskel.core.synthetic.procedural import builtin_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    t0 = time.perf_counter()
    one = builtin_motion("walk")
    motion = builtin_motion("walk", fps=one.fps * args.frames / one.n_frames)
    tracks, truth = synthesize(motion, seed=0)
    est = truth_as_estimate(truth)
    n = len(est.frames)
    print(f"clip: built-in walk, {n} frames, 17 joints (prepared in {time.perf_counter() - t0:.1f} s)")

    scene = bpy.context.scene
    from monoskel.blender import scene_data

    t = time.perf_counter()
    scene_data.store_tracks(scene, tracks)
    scene_data.store_estimate(scene, est)
    stored = time.perf_counter() - t
    t = time.perf_counter()
    build.build_armature(scene, est, height_m=1.75)
    build.build_camera(scene, est, None, height_m=1.75)
    ours_core = time.perf_counter() - t

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    t = time.perf_counter()
    built = build.build_all(scene, est, tracks, height_m=1.75)
    ours_all = time.perf_counter() - t

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "clip.bvh")
        t = time.perf_counter()
        export.export_bvh(scene, built["armature"], path)
        exported = time.perf_counter() - t
        bpy.ops.wm.read_factory_settings(use_empty=True)
        t = time.perf_counter()
        bpy.ops.import_anim.bvh(filepath=path)
        blender_import = time.perf_counter() - t
        imported = [o for o in bpy.data.objects if o.type == 'ARMATURE']
        assert imported and len(imported[0].data.bones) == 16

    print(f"ours: tracks + estimate stored in the .blend {stored:5.2f} s")
    print(f"ours: armature + motion + camera          {ours_core:7.2f} s")
    print(f"ours: build_all (+ 17 track markers, diag) {ours_all:7.2f} s")
    print(f"Blender BVH importer, same clip            {blender_import:7.2f} s   "
          f"(BVH written by Blender's exporter in {exported:.1f} s, untimed)")
    verdict = "faster" if ours_all <= blender_import else "SLOWER"
    print(f"build_all is {blender_import / ours_all:.1f}x the importer's speed ({verdict}); "
          f"Blender {bpy.app.version_string}")
    addon.unregister()
    return 0


if __name__ == "__main__":
    sys.exit(main())
