"""Speed of retargeting a 10,000-frame clip onto a Rigify metarig and generated rig against Blender's BVH import of it.

The clip is the built-in walk sampled at 10,000 frames.  Timed, in one run:

* ours: the whole retarget onto Rigify's human metarig (made by Rigify's own operator): reading the
  rig, the solve (body frames, IK, planted feet) and baking quaternion/Euler keys into one action;
  the solve alone and the bake alone are shown too;
* ours: the same onto the rig Rigify generates from that metarig (its FK controls), map guess included;
* Blender: ``bpy.ops.import_anim.bvh`` loading the same motion (our armature exported to BVH with
  Blender's exporter first, untimed) into an armature.

Also measured: how far feet and hands land from where they were asked to go, and what key reduction
(``--max-error-deg``) keeps.

Run:  python bench/bench_retarget.py [--frames 10000] [--max-error-deg 0.5]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=10_000)
    p.add_argument("--max-error-deg", type=float, default=0.5, help="key reduction bound to report (degrees)")
    return p.parse_args(argv)


def main() -> int:
    args = _args()
    sys.path.insert(0, ROOT)
    import bpy

    import extension_loader

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = extension_loader.load_extension()
    addon.register()
    from monoskel.blender import export
    from monoskel.blender.retarget.apply import bake, retarget_onto, source_motion
    from monoskel.blender.retarget.rig_io import target_rig
    from monoskel.blender.review import takes
    from monoskel.core.retarget import guess_bone_map, retarget
    from monoskel.core.synthetic.procedural import builtin_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate

    one = builtin_motion("walk")
    motion = builtin_motion("walk", fps=one.fps * args.frames / one.n_frames)
    tracks, truth = synthesize(motion, seed=0)
    est = truth_as_estimate(truth)
    scene = bpy.context.scene
    scene.monoskel.height_m = 1.75
    takes.build_take(scene, est, tracks)
    joints, frames, stance, fps = source_motion(scene)
    print(f"clip: built-in walk, {len(frames)} frames at {fps:.0f} fps")

    import addon_utils

    addon_utils.enable("rigify", default_set=True)
    bpy.ops.object.armature_human_metarig_add()
    rig_obj = bpy.context.object
    t = time.perf_counter()
    rig = target_rig(rig_obj)
    bone_map = guess_bone_map(rig)
    t_read = time.perf_counter() - t
    t = time.perf_counter()
    result = retarget(rig, bone_map, joints, fps=fps, stance=stance)
    t_solve = time.perf_counter() - t
    t = time.perf_counter()
    baked = bake(rig_obj, result, frames)
    t_bake = time.perf_counter() - t
    ours = t_read + t_solve + t_bake
    err_mm = 1000 * result.end_error / result.scale
    reduced = bake(rig_obj, result, frames, max_error_deg=args.max_error_deg)

    # smoothing, measured: detector-like jitter (1 cm per joint) and the rotations' frame-to-frame wobble
    from monoskel.core.retarget import RetargetSettings

    noisy = joints + np.random.default_rng(0).normal(scale=0.01, size=joints.shape)

    def wobble(res):      # mean angle between a frame's rotation and the average of its neighbours, degrees
        q = res.rotation
        mid = 0.5 * (q[2:] + q[:-2])
        dot = np.abs(np.sum(mid * q[1:-1], axis=-1)) / np.linalg.norm(mid, axis=-1)
        return float(np.degrees(2 * np.arccos(np.clip(dot, -1, 1))).mean())

    clean = wobble(result)
    rough = wobble(retarget(rig, bone_map, noisy, fps=fps, stance=stance))
    smooth = {hz: wobble(retarget(rig, bone_map, noisy, fps=fps, stance=stance,
                                  settings=RetargetSettings(smooth_hz=hz))) for hz in (4.0, 8.0)}

    # the rig Rigify generates from a fresh metarig (its FK controls hang from constraint-driven
    # mechanism bones); the metarig above carries the bake and would be generated posed
    bpy.ops.object.select_all(action='DESELECT')
    bpy.ops.object.armature_human_metarig_add()
    before = set(bpy.data.objects)
    bpy.ops.pose.rigify_generate()
    generated = next(o for o in bpy.data.objects if o not in before and o.type == 'ARMATURE')
    t = time.perf_counter()
    gen_map = guess_bone_map(target_rig(generated))
    gen_result, gen_baked = retarget_onto(generated, joints, frames, gen_map, fps=fps, stance=stance)
    t_generated = time.perf_counter() - t

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "clip.bvh")
        export.export_bvh(scene, scene.monoskel.armature, path)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        t = time.perf_counter()
        bpy.ops.import_anim.bvh(filepath=path)
        blender_import = time.perf_counter() - t

    print(f"ours: read rig + guess map                  {t_read:7.2f} s")
    print(f"ours: solve ({len(result.bones)} bones, IK, planted feet)   {t_solve:7.2f} s")
    print(f"ours: bake {baked['keys']} rotation keys              {t_bake:7.2f} s")
    print(f"ours: retarget onto the Rigify metarig      {ours:7.2f} s")
    print(f"ours: retarget onto the generated Rigify rig {t_generated:6.2f} s  ({len(gen_result.bones)} FK controls, "
          f"{len(gen_baked['evaluated_bones'])} set frame by frame, check {gen_baked['check_deg']:.4f} deg)")
    print(f"Blender BVH importer, same clip             {blender_import:7.2f} s")
    for name, took in (("metarig", ours), ("generated rig", t_generated)):
        verdict = "faster" if took <= blender_import else "SLOWER"
        print(f"retarget onto the {name} is {blender_import / took:.1f}x the importer's speed ({verdict}); "
              f"Blender {bpy.app.version_string}")
    print(f"feet and hands from their goals: median {np.median(err_mm):.2f} mm, max {err_mm.max():.2f} mm "
          f"(source scale); contact frames L/R {int(result.contact[:, 0].sum())}/{int(result.contact[:, 1].sum())}")
    print(f"key reduction at {args.max_error_deg} deg: {reduced['keys']} of {reduced['keys_before']} keys kept "
          f"({100 * reduced['keys'] / reduced['keys_before']:.1f} %), largest error {reduced['error_deg']:.3f} deg")
    print(f"smoothing: rotation wobble {clean:.3f} deg clean, {rough:.3f} deg with 1 cm joint noise, "
          + ", ".join(f"{v:.3f} deg smoothed at {hz:g} Hz" for hz, v in smooth.items()))
    addon.unregister()
    return 0


if __name__ == "__main__":
    sys.exit(main())
