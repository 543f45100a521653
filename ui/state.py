"""What each sidebar section shows, as plain data: the panels only render these rows.

Blender gives no ``UILayout`` outside a real window, so the *decisions* of the
sidebar (which rows, which labels, which buttons are enabled and why) live here,
in functions of ``scene.monoskel`` that the tests run for every state (no tracks,
tracks, estimating, result, result with truth).  ``ui/panels.py`` turns the rows
into layout calls and holds no logic of its own.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..blender import estimate_job
from ..core.skeleton import CLASSES
from ..operators.common import REASONS, missing_requirement

#: Requirements of each operator button, in the words of ``operators/common.py``.
BUTTON_NEEDS: dict[str, tuple[str, ...]] = {
    "monoskel.import_tracks": ("idle",),
    "monoskel.import_test_data": ("idle", "test_source"),
    "monoskel.clip_add_joint_tracks": ("clip",),
    "monoskel.clip_to_tracks": ("idle", "clip"),
    "monoskel.detect_pose": ("idle", "clip", "detector"),
    "monoskel.animate_from_clip": ("idle", "clip", "detector"),
    "monoskel.animate_cancel": (),
    "monoskel.refine_tracks": ("idle", "tracks", "clip"),
    "monoskel.track_background": ("idle", "tracks", "clip"),
    "monoskel.trim_tracks": ("idle", "tracks"),
    "monoskel.add_view": ("idle", "tracks"),
    "monoskel.load_view_cameras": ("idle", "views"),
    "monoskel.save_view_cameras": ("idle", "views", "estimate"),
    "monoskel.clear_views": ("idle", "views"),
    "monoskel.estimate": ("tracks", "idle"),
    "monoskel.estimate_cancel": (),
    "monoskel.build_armature": ("idle", "estimate"),
    "monoskel.build_camera": ("idle", "estimate"),
    "monoskel.build_all": ("idle", "estimate"),
    "monoskel.build_body": ("idle", "armature"),
    "monoskel.export_bvh": ("idle", "armature"),
    "monoskel.export_fbx": ("idle", "built"),
    "monoskel.refresh": ("idle",),
    "monoskel.pose_from_image": ("tracks", "idle"),
    "monoskel.pose_flip_segment": ("idle", "pose"),
    "monoskel.pose_scale": ("idle", "pose"),
    "monoskel.jump_to_frame": ("estimate",),
    "monoskel.flip_bone_depth": ("idle", "estimate", "motion"),
    "monoskel.plant_foot": ("idle", "estimate", "motion"),
    "monoskel.new_take": ("idle", "estimate"),
    "monoskel.take_make_active": ("idle", "take"),
    "monoskel.take_delete": ("idle", "take"),
    "monoskel.take_compare": ("idle", "take", "other_take"),
    "monoskel.retarget_guess_map": ("idle", "target"),
    "monoskel.retarget": ("idle", "estimate", "target"),
    "monoskel.retarget_save_preset": ("idle", "target"),
    "monoskel.retarget_load_preset": ("idle", "target"),
}


@dataclass(frozen=True)
class Row:
    """One line of a section.

    ``kind`` is "label", "prop" (``attr`` of ``scene.monoskel``), "operator" (``op``),
    "progress" (``value`` 0..1), "table" (``cells``: header row first), "take_list" (the takes) or
    "bone_map" (the retargeting map's rows, each a bone picked from the target rig).
    ``enabled`` False greys the row out; ``reason`` says why, under the button.
    """

    kind: str
    text: str = ""
    attr: str = ""
    op: str = ""
    icon: str = "NONE"
    enabled: bool = True
    reason: str = ""
    value: float = 0.0
    cells: tuple[tuple[str, ...], ...] = ()
    depress: bool = False    # "operator" drawn pressed (a toggle made of an operator)
    op_props: tuple = ()     # "operator" properties to set: ((name, value), ...)


def label(text: str, icon: str = "NONE") -> Row:
    return Row("label", text=text, icon=icon)


def prop(attr: str, text: str = "", enabled: bool = True) -> Row:
    return Row("prop", attr=attr, text=text, enabled=enabled)


def button(op: str, text: str, settings, icon: str = "NONE", *, has_clip: bool = False) -> Row:
    """An operator button whose enabled state and reason match the operator's own ``poll``."""
    needs = BUTTON_NEEDS[op]
    reason = missing_requirement(settings, [n for n in needs if n not in ("clip", "detector")])
    if reason is None and "clip" in needs and not has_clip:
        reason = REASONS["clip"]
    if reason is None and "detector" in needs:
        from ..operators.detect_pose import detector_available

        ok, why = detector_available()
        reason = None if ok else why
    # The estimate buttons also look at the job itself, exactly as their operators' polls do.
    if op == "monoskel.estimate" and reason is None and estimate_job.current() is not None:
        reason = REASONS["idle"]
    if op == "monoskel.estimate_cancel" and estimate_job.current() is None:
        reason = "No estimate is running"
    if op == "monoskel.animate_cancel" and not settings.animate_running:
        reason = "Animate from Clip is not running"
    return Row("operator", op=op, text=text, icon=icon, enabled=reason is None, reason=reason or "")


def _percent(x: float) -> str:
    return f"{100.0 * x:.1f}%"


# ----------------------------------------------------------------------------- sections

def detect_rows(settings, *, has_clip: bool) -> list[Row]:
    """Pose detection on the active clip: its settings, the button, and progress while it runs."""
    rows = [prop("detect_mode", enabled=not settings.detect_running),
            prop("detect_step", enabled=not settings.detect_running),
            button("monoskel.detect_pose", "Detect Pose in Clip", settings, "POSE_HLT", has_clip=has_clip)]
    if settings.detect_running:
        rows.append(Row("progress", text=settings.detect_message or "Detecting", value=settings.detect_progress))
    elif settings.detect_message:
        rows.append(label(f"Last detection: {settings.detect_message}"))
    return rows


def animate_rows(settings, *, has_clip: bool) -> list[Row]:
    """The one button from footage to animation: its option, progress and Cancel while it runs, and what
    each stage of the last run found."""
    rows = [prop("animate_background", enabled=not settings.animate_running),
            button("monoskel.animate_from_clip", "Animate from Clip", settings, "PLAY", has_clip=has_clip)]
    if settings.animate_running:
        rows.append(Row("progress", text=settings.animate_message or "Starting", value=settings.animate_progress))
        rows.append(button("monoskel.animate_cancel", "Cancel", settings, "CANCEL"))
        return rows
    if settings.animate_message:
        rows.append(label(f"Last run: {settings.animate_message}"))
    rows += [label(line, "ERROR" if line.startswith("background: ") and "person alone" in line else "INFO")
             for line in settings.animate_summary.split("\n") if line]
    return rows


def input_rows(settings, *, has_clip: bool = False) -> list[Row]:
    rows = animate_rows(settings, has_clip=has_clip)
    rows.append(button("monoskel.import_tracks", "Import Tracks...", settings, "IMPORT"))
    rows += detect_rows(settings, has_clip=has_clip)
    rows.append(button("monoskel.clip_to_tracks", "Tracks from Movie Clip", settings, "TRACKER", has_clip=has_clip))
    if not settings.has_tracks:
        rows.append(label("No tracks yet: import a file, use a movie clip or make test data", "INFO"))
        rows.append(button("monoskel.refresh", "Refresh from Scene Data", settings, "FILE_REFRESH"))
        return rows
    rows.append(button("monoskel.refine_tracks", "Refine Tracks on Footage", settings, "TRACKING_REFINE_FORWARDS",
                       has_clip=has_clip))
    rows.append(button("monoskel.track_background", "Track Background", settings, "TRACKING", has_clip=has_clip))
    rows += [
        label(f"Source: {settings.tracks_source}", "FILE"),
        label(f"Frames: {settings.tracks_frames} (from scene frame {settings.tracks_first_frame})"),
        label(f"FPS: {settings.tracks_fps:g}"),
        label(f"Image: {settings.tracks_width} x {settings.tracks_height} px"),
        label(f"Joints present: {settings.tracks_joints_present}/17"),
        label(f"Background tracks: {settings.tracks_static}" if settings.tracks_static else
              "Background tracks: none (the camera comes from the person)"),
        label(f"Missing: {_percent(settings.tracks_missing)}",
              "ERROR" if settings.tracks_missing > 0.5 else "NONE"),
        button("monoskel.trim_tracks", "Trim Tracks to Scene Range", settings, "ARROW_LEFTRIGHT"),
    ]
    return rows


def views_rows(settings) -> list[Row]:
    """Further synchronized cameras filming the same person (the multi-view estimate)."""
    rows = []
    if settings.views_count == 0:
        rows.append(label("One camera: the scene's tracks alone", "INFO"))
    else:
        rows += [label(f"Views: {settings.views_count + 1} (the scene's tracks and {settings.views_count} more)",
                       "OUTLINER_OB_CAMERA"),
                 label(f"From: {settings.views_sources}"),
                 label("Cameras: given by the calibration file" if settings.views_cameras_given else
                       "Cameras: calibrated from the person when estimating")]
    rows.append(button("monoskel.add_view", "Add View Tracks...", settings, "ADD"))
    rows.append(button("monoskel.load_view_cameras", "Load View Cameras...", settings, "IMPORT"))
    rows.append(button("monoskel.save_view_cameras", "Save View Cameras...", settings, "EXPORT"))
    rows.append(button("monoskel.clear_views", "Clear Views", settings, "X"))
    return rows


def test_data_rows(settings) -> list[Row]:
    rows = [prop("test_source")]
    if settings.test_source == "FILE":
        rows.append(prop("test_bvh_path"))
    rows += [prop("test_kinds"), prop("test_noise_px"), prop("test_dropout"), prop("test_seed"),
             prop("test_max_frames")]
    rows.append(button("monoskel.import_test_data", "Make Test Data", settings, "ARMATURE_DATA"))
    return rows


def camera_rows(settings) -> list[Row]:
    rows = [prop("estimate_focal"), prop("focal_mm", "Initial Focal (mm)", enabled=not settings.estimate_focal),
            prop("use_background", enabled=settings.tracks_static > 0)]
    if settings.has_estimate:
        for text in (settings.est_scene_camera, settings.est_blender_solve):
            if text:
                rows.append(label(text, "TRACKER"))
        spells = [s for s in settings.est_spells.split("; ") if s]
        if spells:
            rows.append(label(f"Detected camera spells ({len(spells)}):"))
            rows += [label(f"  frames {s}") for s in spells]
        else:
            rows.append(label("No camera spells reported by the method"))
        if not settings.est_focal_determined:
            rows.append(label("Focal length not determined: the camera did not turn enough, nothing static "
                              "was tracked, or a phone's lens was assumed (see the warnings)", "ERROR"))
            if settings.estimate_focal:
                # measured: the lens given steadies planted feet and depth most (docs/motion.md)
                rows.append(label(f"Assumed about {settings.est_focal_mm:.0f} mm. Know the lens? Untick Estimate "
                                  "Focal Length, enter it and estimate again", "INFO"))
    return rows


def estimate_rows(settings) -> list[Row]:
    rows = [prop("method", enabled=not settings.estimate_running)]
    if settings.estimate_running:
        rows.append(Row("progress", text=settings.estimate_message or "Estimating",
                        value=float(settings.estimate_progress)))
        rows.append(button("monoskel.estimate_cancel", "Cancel", settings, "CANCEL"))
    else:
        rows.append(button("monoskel.estimate", "Estimate", settings, "PLAY"))
        if settings.estimate_message:
            rows.append(label(f"Last run: {settings.estimate_message}"))
    return rows


def results_rows(settings) -> list[Row]:
    if not settings.has_estimate:
        return [label(REASONS["estimate"] if settings.has_tracks else REASONS["tracks"], "INFO")]
    rows = [label(f"Method: {settings.est_method}"),
            label(f"Focal length: {settings.est_focal_mm:.1f} mm (36 mm equivalent)")]
    if settings.has_truth and settings.truth_focal_mm > 0:
        err = 100.0 * (settings.est_focal_mm - settings.truth_focal_mm) / settings.truth_focal_mm
        rows.append(label(f"True focal (mean): {settings.truth_focal_mm:.1f} mm ({err:+.1f}%)"))
    est = list(settings.est_proportions)
    if settings.has_truth:
        truth = list(settings.truth_proportions)
        cells = [("Class", "Estimate", "Truth", "Error")]
        for k, name in enumerate(CLASSES):
            err = 100.0 * (est[k] - truth[k]) / truth[k] if truth[k] > 0 else float("nan")
            cells.append((name, f"{est[k]:.4f}", f"{truth[k]:.4f}", f"{err:+.1f}%"))
        mean_abs = sum(abs(est[k] - truth[k]) / truth[k] for k in range(len(CLASSES)) if truth[k] > 0)
        rows.append(Row("table", cells=tuple(cells)))
        rows.append(label(f"Mean |error|: {100.0 * mean_abs / len(CLASSES):.2f}%"))
    else:
        cells = [("Class", "Proportion")] + [(name, f"{est[k]:.4f}") for k, name in enumerate(CLASSES)]
        rows.append(Row("table", cells=tuple(cells)))
    for warning in (w for w in settings.est_warnings.split("; ") if w):
        rows.append(label(warning, "ERROR"))
    worst = [w.split(":") for w in settings.est_worst_frames.split(",") if ":" in w]
    if worst:
        rows.append(label("Worst-fitting frames (click to go there):"))
        for index, px in worst:
            frame = int(index) + int(settings.tracks_first_frame)
            rows.append(_with(button("monoskel.jump_to_frame", f"Frame {frame}: {px} px", settings, "TIME"),
                              op_props=(("frame", frame),)))
    if settings.est_has_motion:
        rows.append(button("monoskel.flip_bone_depth", "Flip Bone Depth...", settings, "MOD_MIRROR"))
        rows.append(button("monoskel.plant_foot", "Plant Foot...", settings, "PINNED"))
    return rows


def build_rows(settings) -> list[Row]:
    rows = [prop("height_m"), prop("build_armature"), prop("build_motion", enabled=settings.build_armature),
            prop("build_camera"), prop("build_tracks_view", enabled=settings.build_camera)]
    if settings.has_estimate and not settings.est_has_motion and settings.build_motion:
        rows.append(label("No 3D motion in this estimate: the armature stays in its rest pose", "INFO"))
    rows += [button("monoskel.build_all", "Build", settings, "OUTLINER_OB_ARMATURE"),
             button("monoskel.build_armature", "Armature Only", settings, "ARMATURE_DATA"),
             button("monoskel.build_camera", "Camera Only", settings, "CAMERA_DATA")]
    if settings.armature is not None:
        rows.append(label(f"Armature: {settings.armature.name}", "OUTLINER_OB_ARMATURE"))
        rows.append(button("monoskel.build_body", "Build Body", settings, "META_BALL"))
    if settings.camera is not None:
        rows.append(label(f"Camera: {settings.camera.name}", "OUTLINER_OB_CAMERA"))
    return rows


def single_image_rows(settings) -> list[Row]:
    """Pose from one image: the button, then the posed frame, the scale and one depth toggle per segment
    (operators, so each click re-poses at once)."""
    from ..core.single_image import SEGMENT_NAMES

    rows = [button("monoskel.pose_from_image", "Pose from Image", settings, "POSE_HLT")]
    if not settings.si_has_pose:
        rows.append(label("Poses the current frame from its joints alone", "INFO"))
        return rows
    rows += [label(f"Posed frame {settings.si_frame}"),
             _with(button("monoskel.pose_scale", f"Scale: {settings.si_scale:.1f} px/m", settings, "ARROW_LEFTRIGHT")),
             label(f"Smallest scale that fits: {settings.si_scale_min:.1f}"),
             label("Depth (pressed: far end farther away); ! either fits", "INFO")]
    ambiguous = {a.strip() for a in settings.si_ambiguous.split(",")}
    for k, name in enumerate(SEGMENT_NAMES):
        rows.append(_with(button("monoskel.pose_flip_segment", name, settings,
                                 "ERROR" if name in ambiguous else "NONE"),
                          depress=bool(settings.si_signs[k]), op_props=(("index", k),)))
    return rows


def _comparison_rows(settings) -> list[Row]:
    """The last Compare (:meth:`core.review.take_compare.TakeComparison.summary`): which takes, how far
    their joints are apart, the worst frames and the bones."""
    import json

    try:
        summary = json.loads(settings.take_compare)
        names = settings.take_compare_names.split("\n") + ["", ""]
        rows = [label(f"A: {names[0]}", "TRIA_RIGHT"), label(f"B: {names[1]}", "TRIA_RIGHT")]
        if not summary["frames"]:
            return rows + [label("The takes share no posed frame", "INFO")]
        rows.append(label(f"Joints apart: {summary['mean_mm']:.0f} mm mean, {summary['max_mm']:.0f} mm max "
                          f"({summary['frames']} frames)"))
        joints = ", ".join(f"{name} {mm:.0f}" for name, mm in summary["worst_joints"])
        rows.append(label(f"Most apart: {joints} mm"))
        first = int(settings.tracks_first_frame)
        for frame, mm in summary["worst_frames"]:
            rows.append(_with(button("monoskel.jump_to_frame", f"Frame {frame + first}: {mm:.0f} mm", settings,
                                     "TIME"), op_props=(("frame", frame + first),)))
        rows.append(Row("table", cells=tuple(tuple(r) for r in summary["rows"])))
    except (ValueError, KeyError, TypeError):
        return []
    return rows


def takes_rows(settings) -> list[Row]:
    """The take list, its buttons, the residual-lines toggle and the last comparison."""
    rows = [Row("take_list")]
    active = settings.take_active
    if 0 <= active < len(settings.takes):
        rows.append(label(f"Active: {settings.takes[active].name}", "RADIOBUT_ON"))
    rows += [button("monoskel.new_take", "New Take", settings, "ADD"),
             button("monoskel.take_make_active", "Make Active", settings, "RADIOBUT_ON"),
             button("monoskel.take_compare", "Compare with Active", settings, "ARROW_LEFTRIGHT"),
             button("monoskel.take_delete", "Delete Take", settings, "TRASH"),
             prop("show_residuals")]
    if settings.take_compare:
        rows += _comparison_rows(settings)
    return rows


def retarget_rows(settings) -> list[Row]:
    """The target rig, its bone map (editable), the options and the button."""
    rows = [prop("retarget_target"), button("monoskel.retarget_guess_map", "Guess Bone Map", settings, "BONE_DATA")]
    target = settings.retarget_target
    if target is not None and target.type == "ARMATURE" and settings.retarget_map_rig == target.name:
        rows.append(Row("bone_map"))
    rows += [prop("retarget_plant_feet"), prop("retarget_blend_frames", enabled=settings.retarget_plant_feet),
             prop("retarget_ik_hands"), prop("retarget_smooth_hz"), prop("retarget_max_error_deg"),
             button("monoskel.retarget", "Retarget", settings, "ARMATURE_DATA"),
             button("monoskel.retarget_save_preset", "Save Preset...", settings, "EXPORT"),
             button("monoskel.retarget_load_preset", "Load Preset...", settings, "IMPORT")]
    if settings.retarget_summary:
        rows.append(label(settings.retarget_summary, "INFO"))
    return rows


def _with(row: Row, **changes) -> Row:
    from dataclasses import replace

    return replace(row, **changes)


def export_rows(settings) -> list[Row]:
    return [button("monoskel.export_bvh", "Export BVH...", settings, "EXPORT"),
            button("monoskel.export_fbx", "Export FBX...", settings, "EXPORT")]


def clip_rows(settings, *, has_clip: bool) -> list[Row]:
    """The Movie Clip Editor's MonoSkel panel."""
    return [*animate_rows(settings, has_clip=has_clip), *detect_rows(settings, has_clip=has_clip),
            label("Tracks named after the 17 joints"),
            button("monoskel.clip_add_joint_tracks", "Add Joint Tracks", settings, "ADD", has_clip=has_clip),
            button("monoskel.clip_to_tracks", "Tracks from Clip", settings, "TRACKER", has_clip=has_clip),
            button("monoskel.refine_tracks", "Refine Tracks on Footage", settings, "TRACKING_REFINE_FORWARDS",
                   has_clip=has_clip),
            button("monoskel.track_background", "Track Background", settings, "TRACKING", has_clip=has_clip)]


SECTIONS = {
    "input": input_rows,
    "test_data": test_data_rows,
    "views": views_rows,
    "camera": camera_rows,
    "estimate": estimate_rows,
    "results": results_rows,
    "build": build_rows,
    "takes": takes_rows,
    "retarget": retarget_rows,
    "single_image": single_image_rows,
    "export": export_rows,
    "clip": clip_rows,
}


def section_rows(section: str, settings, *, has_clip: bool = False) -> list[Row]:
    fn = SECTIONS[section]
    if section in ("input", "clip"):
        return fn(settings, has_clip=has_clip)
    return fn(settings)
