"""Reopen the demo's .blend with ``bpy.ops.wm.open_mainfile`` and print what it holds.

This is the proof that ``make demo`` produced a real Blender file: objects with their types,
the armature's bones and lengths, the camera's lens and sensor, the actions and their keys, and a
summary of the result JSON.  Missing parts (no armature yet, no camera animation) are printed
plainly as MISSING; only a file that does not open, or opens empty, is an error.

    python tools/check_demo.py out/demo.blend [out/demo_result.json]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _fcurves(action):
    """F-curves of an action on Blender 4.2-5.0 (legacy ``action.fcurves`` or layered channelbags)."""
    curves = list(getattr(action, "fcurves", None) or [])
    for layer in getattr(action, "layers", []):
        for strip in layer.strips:
            for bag in getattr(strip, "channelbags", []):
                curves.extend(bag.fcurves)
    return curves


def describe_blend(path: Path) -> list[str]:
    import bpy

    bpy.ops.wm.open_mainfile(filepath=str(path))
    scene = bpy.context.scene
    lines = [
        f"{path}: opened with Blender {bpy.app.version_string}",
        f"scene {scene.name!r}: frames {scene.frame_start}-{scene.frame_end} at {scene.render.fps} fps",
    ]
    objects = list(bpy.data.objects)
    counts = {}
    for obj in objects:
        counts[obj.type] = counts.get(obj.type, 0) + 1
    lines.append("objects: " + ", ".join(f"{n} {kind.lower()}" for kind, n in sorted(counts.items())))
    shown_actions = set()
    for obj in objects:
        if obj.type not in ("ARMATURE", "CAMERA"):
            continue
        action = obj.animation_data.action if obj.animation_data else None
        lines.append(f"  {obj.type.lower()} {obj.name!r}: action {action.name if action else None!r}")
        if obj.type == "ARMATURE":
            bones = obj.data.bones
            lines.append(f"    {len(bones)} bones, lengths in m:")
            lines.extend(f"      {b.name:24} {b.length:.3f}" for b in bones)
        else:
            cam = obj.data
            lines.append(f"    lens {cam.lens:.1f} mm, sensor width {cam.sensor_width:.1f} mm")
            lens_action = cam.animation_data.action if cam.animation_data else None
            if lens_action:
                lines.append(f"    lens action {lens_action.name!r}")
                shown_actions.add(lens_action.name)
        if action:
            shown_actions.add(action.name)
    other_keys = 0
    for action in bpy.data.actions:
        curves = _fcurves(action)
        keys = sum(len(c.keyframe_points) for c in curves)
        if action.name in shown_actions:
            lines.append(f"  action {action.name!r}: {len(curves)} f-curves, {keys} keys")
        else:
            other_keys += keys
    others = len(bpy.data.actions) - len(shown_actions & {a.name for a in bpy.data.actions})
    if others:
        lines.append(f"  {others} other actions (e.g. track markers), {other_keys} keys")
    texts = [t.name for t in bpy.data.texts]
    if texts:
        lines.append(f"  texts: {', '.join(texts)}")
    kinds = {obj.type for obj in objects}
    for kind in ("ARMATURE", "CAMERA"):
        if kind not in kinds:
            lines.append(f"  MISSING: no {kind.lower()} object in the file")
    if not bpy.data.actions:
        lines.append("  MISSING: no animation (actions) in the file")
    if not objects:
        raise SystemExit(f"error: {path} opened but holds no objects")
    return lines


def describe_result(path: Path) -> list[str]:
    data = json.loads(path.read_text())
    lines = [f"{path}: {data.get('format')} v{data.get('version')}, method {data.get('method')!r}"]
    proportions = data.get("proportions") or {}
    if proportions:
        lines.append("  proportions: " + ", ".join(f"{k} {v:.3f}" for k, v in proportions.items()))
    frames = data.get("frames") or []
    moving = sum(1 for f in frames if f.get("camera_moving"))
    lines.append(f"  focal {data.get('focal_mm')} mm, {len(frames)} frames, camera moving in {moving}")
    for key, value in data.items():
        if key not in ("format", "version", "method", "proportions", "frames", "focal_mm"):
            lines.append(f"  {key}: {json.dumps(value)[:200]}")
    return lines


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__)
        return 2
    blend = Path(argv[0])
    if not blend.is_file():
        print(f"error: {blend} does not exist", file=sys.stderr)
        return 1
    lines = describe_blend(blend)
    if len(argv) > 1 and Path(argv[1]).is_file():
        lines += describe_result(Path(argv[1]))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
