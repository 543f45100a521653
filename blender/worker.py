"""The whole headless job as plain functions: input -> estimate -> scene -> files.

``batch.py`` parses the command line and calls :func:`run_job`; operators may
call the same steps.  Every step talks through ``report(level, message)``
(levels 'INFO', 'WARNING', like Blender's own ``io_anim_bvh``), raises
:class:`core.errors.InputError` for anything the user can fix, and validates
all inputs and output folders before it writes anything, so bad input never
leaves an output file behind.  ``bpy`` is imported only inside the steps
that need it, so ``batch.py`` can reject bad arguments before starting Blender.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

from ..core.errors import InputError
from ..core.io.file_io import check_output_file
from ..core.lens.prior import describe as describe_lens
from ..core.result import Estimate, read_estimate_json, write_estimate_json
from ..core.review.report import write_review_html
from ..core.skeleton import CLASSES
from ..core.synthetic.truth import truth_as_estimate

TRUTH_METHOD = "truth"


@dataclass
class JobOptions:
    """What to do; mirrors batch.py's command line."""

    output: str
    input: str | None = None          # tracks file (any supported format) or .bvh
    builtin: str | None = None        # built-in motion name instead of input
    estimate: str | None = None       # skeleton-estimate JSON to build instead of estimating
    bvh: str | None = None
    fbx: str | None = None
    result: str | None = None
    method: str | None = None
    focal_mm: float | None = None
    height_m: float = 1.75
    kinds: tuple[str, ...] = ("pan", "tilt", "zoom")
    noise_px: float = 1.0
    dropout: float = 0.0
    seed: int = 0
    max_frames: int | None = None
    format: str | None = None
    fps: float | None = None
    image_size: tuple[float, float] | None = None
    min_confidence: float = 0.0
    static_points: int = 0            # motion input: static background points filmed too
    use_background: bool = True       # estimate with the tracks' background points when they have some
    review: bool = True               # write the review report (report_path) beside the .blend
    target_rig: str | None = None     # "FILE.blend:ARMATURE": also retarget onto that rig
    views: tuple[str, ...] = ()       # further synchronized views (tracks files): a multi-view estimate
    calibration: str | None = None    # their cameras (multiview-calibration JSON); default: from the person
    video: str | None = None          # a video (or first image of a sequence): detect the pose first
    detect_mode: str = "tracking"     # tracking or per-frame (core.pose_detection.tracker.MODES)
    detect_step: int = 1              # detect on every n-th frame
    tracks_out: str | None = None     # also write the detected tracks (skeleton-tracks JSON)
    frame_range: str | None = None    # "A-B": only the tracks' frames A..B (0-based), e.g. one person's stretch
    track_background: bool = False    # asked for by name (--track-background); footage is followed anyway
    footage: str | None = None        # the footage of a tracks file (video or first image); --video's own by default


def report_path(output: str) -> str:
    """Where the headless review report goes: beside the .blend, ``OUT.review.html``."""
    return os.path.splitext(output)[0] + ".review.html"


@dataclass
class JobResult:
    estimate: Estimate
    truth: object | None
    objects: dict
    written: list[str]


def _quiet(level, message):
    pass


# ----------------------------------------------------------------------------- validation

def _check_out(path: str | None, ext: str, what: str) -> None:
    if path is None:
        return
    if not path.lower().endswith(ext):
        raise InputError(f"{path}: {what} must end in {ext}")
    check_output_file(path, what)


def validate(opts: JobOptions) -> None:
    """Everything that can be checked before reading or writing anything."""
    sources = [s for s in (opts.input, opts.builtin, opts.video) if s]
    if len(sources) != 1:
        raise InputError("give exactly one input: a tracks file, a .bvh file, --builtin NAME or --video FILE")
    for path in (opts.input, opts.video):
        if path and not os.path.isfile(path):
            raise InputError(f"{path}: no such file")
    if opts.video:
        from ..core.pose_detection.tracker import MODES

        if opts.detect_mode not in MODES:
            raise InputError(f"--detect-mode must be one of {', '.join(MODES)}, got {opts.detect_mode!r}")
        if not (isinstance(opts.detect_step, int) and opts.detect_step >= 1):
            raise InputError(f"--detect-step must be 1 or more, got {opts.detect_step!r}")
        if opts.views:
            raise InputError("--video detects one view; --views takes tracks files")
    elif opts.tracks_out:
        raise InputError("--tracks-out writes detected tracks: it needs --video")
    if opts.footage and not os.path.isfile(opts.footage):
        raise InputError(f"{opts.footage}: no such file")
    if opts.footage and (opts.video or is_motion_input(opts)):
        raise InputError("--footage is the video of a tracks file; with --video that video is the footage, "
                         "and a filmed motion has none")
    if opts.track_background and not opts.use_background:
        raise InputError("--track-background and --no-background ask for opposite things; give one")
    if opts.track_background and opts.video and opts.detect_step != 1:
        raise InputError("--track-background follows features frame by frame: leave --detect-step at 1")
    if opts.track_background and not (opts.video or opts.footage):
        raise InputError("--track-background follows features on the footage: give --video, or --footage "
                         "with a tracks file")
    _check_out(opts.tracks_out, ".json", "--tracks-out")
    if opts.estimate and not os.path.isfile(opts.estimate):
        raise InputError(f"{opts.estimate}: no such file")
    if not opts.output:
        raise InputError("--output OUT.blend is required")
    _check_out(opts.output, ".blend", "--output")
    _check_out(opts.bvh, ".bvh", "--bvh")
    _check_out(opts.fbx, ".fbx", "--fbx")
    _check_out(opts.result, ".json", "--result")
    if not (isinstance(opts.height_m, (int, float)) and math.isfinite(opts.height_m) and 0.3 <= opts.height_m <= 3.0):
        raise InputError(f"--height-m must be between 0.3 and 3 metres, got {opts.height_m!r}")
    if opts.focal_mm is not None and not (math.isfinite(opts.focal_mm) and opts.focal_mm > 0):
        raise InputError(f"--focal-mm must be a positive number, got {opts.focal_mm!r}")
    if opts.method is not None and not opts.estimate:
        from ..core.estimate import METHODS

        if opts.method not in METHODS and opts.method != TRUTH_METHOD:
            raise InputError(f"unknown method {opts.method!r}; choose one of {sorted(METHODS) + [TRUTH_METHOD]}")
    if opts.views or opts.calibration:
        if not opts.views:
            raise InputError("--calibration needs --views (the further views it calibrates)")
        if is_motion_input(opts):
            raise InputError("--views takes tracks files: give the first view's tracks as the input")
        if opts.estimate or opts.method:
            raise InputError("--views runs the multi-view estimate: leave out --estimate and --method")
        for path in list(opts.views) + ([opts.calibration] if opts.calibration else []):
            if not os.path.isfile(path):
                raise InputError(f"{path}: no such file")
    if opts.max_frames is not None and opts.max_frames < 2:
        raise InputError(f"--frames must be at least 2, got {opts.max_frames}")
    if opts.frame_range is not None:
        from ..core.cli.estimate import parse_frame_range

        parse_frame_range(opts.frame_range, "--frame-range")   # its own one-line error when malformed
        if is_motion_input(opts) or opts.views or opts.max_frames is not None:
            raise InputError("--frame-range takes a stretch of a tracks file or a video's detection; "
                             "not with a .bvh / --builtin, --views or --frames")
    if not 0 <= opts.static_points <= 1000:
        raise InputError(f"--static-points must be between 0 and 1000, got {opts.static_points}")
    if opts.static_points and not is_motion_input(opts):
        raise InputError("--static-points films a motion: it needs a .bvh or --builtin input")
    if opts.target_rig is not None:
        split_rig_spec(opts.target_rig)


def split_rig_spec(spec: str) -> tuple[str, str]:
    """("FILE.blend", "ARMATURE") from --target-rig FILE.blend:ARMATURE (the file must exist)."""
    path, sep, name = spec.rpartition(":")
    if not sep or not path.lower().endswith(".blend") or not name:
        raise InputError(f"--target-rig must look like FILE.blend:ARMATURE, got {spec!r}")
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file (--target-rig)")
    return path, name


def append_rig(scene, spec: str):
    """Append the armature object named in ``spec`` from its .blend into ``scene``; returns it."""
    import bpy

    path, name = split_rig_spec(spec)
    with bpy.data.libraries.load(os.path.abspath(path), link=False) as (source, dest):
        if name not in source.objects:
            raise InputError(f"{path} has no object {name!r} (objects: {', '.join(sorted(source.objects)[:12])})")
        dest.objects = [name]
    obj = dest.objects[0]
    if obj.type != 'ARMATURE':
        bpy.data.objects.remove(obj)
        raise InputError(f"{path}:{name} is a {obj.type.lower()}, not an armature")
    scene.collection.objects.link(obj)
    return obj


def retarget_job(scene, spec: str, report=_quiet):
    """Retarget the active take onto the rig of ``spec`` (its stored bone map, or a guess)."""
    from .retarget.apply import retarget_onto, source_motion
    from .retarget.bone_map_store import stored_or_guessed

    obj = append_rig(scene, spec)
    bone_map = stored_or_guessed(obj)[0]
    joints, frames, stance, fps = source_motion(scene)
    said = [0]

    def progress(fraction):          # a frame-by-frame bake (a generated Rigify rig): a line every 10 %
        if int(10 * fraction) > said[0]:
            said[0] = int(10 * fraction)
            report('INFO', f"retarget: {10 * said[0]} % baked")

    result, baked = retarget_onto(obj, joints, frames, bone_map, fps=fps, stance=stance, progress=progress)
    scene.monoskel.retarget_target = obj
    report('INFO', f"retargeted onto '{obj.name}': {len(result.bones)} bones, {baked['keys']} keys "
                   f"in action '{baked['action'].name}'")
    for note in result.notes:
        report('INFO', note)
    return obj


# ----------------------------------------------------------------------------- steps

def is_motion_input(opts: JobOptions) -> bool:
    return bool(opts.builtin) or (opts.input is not None and opts.input.lower().endswith(".bvh"))


def detect_video(opts: JobOptions, report=_quiet, scene=None):
    """Tracks found by the pose detector in ``opts.video``; the clip and its joint markers stay in the scene."""
    import bpy

    from .pose_detection.clip_detect import detect_clip, load_clip, rotation_warning

    clip = load_clip(opts.video)
    scene = scene or bpy.context.scene
    turned = rotation_warning(clip)
    if turned:
        report('WARNING', turned)
    try:
        report('INFO', f"detecting the pose in {opts.video} ({clip.frame_duration} frames, "
               f"{clip.size[0]}x{clip.size[1]}, {opts.detect_mode})")
        result = detect_clip(clip, step=opts.detect_step, mode=opts.detect_mode, report=report, fps=opts.fps)
    except BaseException:
        bpy.data.movieclips.remove(clip)
        raise
    for note in result.notes:
        report('WARNING', note)
    report('INFO', f"person found in {100 * result.found_share:.0f} % of {len(result.frame_numbers)} frames, "
           f"{len(result.frame_numbers) / max(result.seconds, 1e-9):.1f} frames/s")
    scene.active_clip = clip
    return result.tracks


def load_input(opts: JobOptions, report=_quiet):
    """(tracks, truth or None): read a tracks file, detect them in a video, or film a motion;
    ``--frame-range`` cuts the tracks to a stretch (where it starts is in ``meta["frame_offset"]``)."""
    tracks, truth = _load_whole_input(opts, report)
    if opts.frame_range is not None:
        from ..core.cli.estimate import parse_frame_range

        tracks = tracks.frames_between(*parse_frame_range(opts.frame_range, "--frame-range"))
        report('INFO', f"using frames {opts.frame_range} of the tracks ({tracks.n_frames} frames)")
    if follows_background(opts):
        if opts.video and opts.detect_step != 1:
            report('WARNING', f"background not followed: the person was detected on one frame in "
                              f"{opts.detect_step} and the background is followed frame by frame; the camera "
                              "comes from the person alone")
        else:
            tracks = track_background_on_footage(opts, tracks, report)
    return tracks, truth


def follows_background(opts: JobOptions) -> bool:
    """Whether the run follows the footage's background: whenever there is footage, unless --no-background."""
    return bool(opts.use_background and (opts.video or opts.footage) and not is_motion_input(opts))


#: Where :func:`track_background_on_footage` leaves the fallback warning for the estimate's warnings.
FALLBACK_META = "background_fallback"


def with_background_warning(est: Estimate, tracks) -> Estimate:
    """``est`` with the background's fallback warning (if the tracks carry one) first among its warnings."""
    said = tracks.meta.get(FALLBACK_META)
    if said:
        warnings = est.diagnostics.setdefault("warnings", [])
        if said not in warnings:
            warnings.insert(0, said)
    return est


def track_background_on_footage(opts: JobOptions, tracks, report=_quiet):
    """``tracks`` with the background features Blender's tracker follows on the footage (``--footage``, or the
    clip ``--video`` left in the scene) as their static tracks; the features stay on the clip."""
    import bpy

    from ..core.background_tracking.verdict import FALLBACK
    from .background_tracking import track_background
    from .pose_detection.clip_detect import load_clip

    scene = bpy.context.scene
    clip = scene.active_clip if opts.video else load_clip(opts.footage)
    scene.active_clip = clip
    first = 1 + int(tracks.meta.get("frame_offset", 0) or 0)
    started = time.perf_counter()
    static, found = track_background(bpy.context, clip, tracks, first_clip_frame=first)
    took = time.perf_counter() - started
    report('WARNING' if found.frames_under_four and static is not None else 'INFO',
           f"background followed in {took:.1f} s: {found.summary()}")
    if static is None:
        if tracks.static is not None:
            report('WARNING', f"{found.fallback.removesuffix(FALLBACK)}; the tracks' own "
                              f"{tracks.static.n_points} background tracks give the camera")
            return tracks
        # said once, among the estimate's warnings (with_background_warning)
        return tracks.replaced(meta={**tracks.meta, FALLBACK_META: found.fallback})
    if tracks.static is not None:
        report('WARNING', f"the tracks' own {tracks.static.n_points} background tracks are replaced by the ones "
                          "followed on the footage")
    return tracks.replaced(static=static)


def _load_whole_input(opts: JobOptions, report=_quiet):
    if opts.video:
        tracks = detect_video(opts, report)
        return _at_most(tracks, opts.max_frames), None
    if is_motion_input(opts):
        from ..core.synthetic.motion import BUILTIN_PREFIX, load_motion
        from ..core.synthetic.synth import synthesize

        source = f"{BUILTIN_PREFIX}{opts.builtin}" if opts.builtin else opts.input
        report('INFO', f"loading motion {source}")
        motion = load_motion(source, height_m=opts.height_m, max_frames=opts.max_frames)
        report('INFO', f"filming {motion.n_frames} frames (camera: {', '.join(opts.kinds)}, "
               f"noise {opts.noise_px} px, drop-out {opts.dropout:.0%}, seed {opts.seed})")
        tracks, truth = synthesize(motion, kinds=tuple(opts.kinds), noise_px=opts.noise_px, dropout=opts.dropout,
                                   seed=opts.seed, focal_mm=opts.focal_mm or 50.0, static_points=opts.static_points)
        return tracks, truth
    report('INFO', f"reading tracks {opts.input}")
    tracks = read_tracks_any(opts.input, fmt=opts.format, fps=opts.fps, image_size=opts.image_size,
                             min_confidence=opts.min_confidence)
    return _at_most(tracks, opts.max_frames), None


def _at_most(tracks, max_frames: int | None):
    """The first ``max_frames`` frames of ``tracks`` (``--frames``), background tracks included."""
    if max_frames is None or tracks.n_frames <= max_frames:
        return tracks
    return tracks.frames_between(0, max_frames - 1)


def read_tracks_any(path: str, *, fmt=None, fps=None, image_size=None, min_confidence=0.0):
    """Any format the core reads (core.io.formats.read_any)."""
    from ..core.io.formats import read_any

    return read_any(path, format=fmt, fps=fps, image_size=image_size, min_confidence=min_confidence)


def read_views(opts: JobOptions):
    """(further views' tracks, cameras of all views or None) from ``--views`` / ``--calibration``."""
    if not opts.views:
        return [], None
    from ..core.multiview import read_calibration

    others = [read_tracks_any(p, fmt=opts.format, fps=opts.fps, image_size=opts.image_size,
                              min_confidence=opts.min_confidence) for p in opts.views]
    return others, (read_calibration(opts.calibration) if opts.calibration else None)


def run_estimate(tracks, truth, opts: JobOptions, report=_quiet, views=None) -> Estimate:
    """Run the chosen estimator (or, with ``--method truth``, dress the generator's truth as the estimate).

    ``views``: :func:`read_views`'s result (read here when None)."""
    if opts.estimate:
        report('INFO', f"using the existing estimate {opts.estimate}")
        est = read_estimate_json(opts.estimate)
        if len(est.frames) != tracks.n_frames:
            raise InputError(f"{opts.estimate}: {len(est.frames)} frames but the tracks have {tracks.n_frames}")
        return est
    if opts.views:
        from ..core.multiview import estimate_multiview

        others, cameras = views if views is not None else read_views(opts)
        report('INFO', f"estimating from {1 + len(others)} views (cameras "
               f"{'from ' + opts.calibration if cameras else 'calibrated from the person'})")
        return estimate_multiview([tracks] + others, cameras=cameras, height_m=opts.height_m)
    if opts.method == TRUTH_METHOD:
        if truth is None:
            raise InputError("--method truth needs a .bvh or --builtin input (tracks files carry no truth)")
        return truth_as_estimate(truth, TRUTH_METHOD)
    from ..core.estimate import DEFAULT_METHOD, estimate

    name = opts.method or DEFAULT_METHOD

    last = [-1.0]

    def progress(fraction, message=""):
        if fraction - last[0] >= 0.1 or fraction >= 1.0:
            last[0] = fraction
            report('INFO', f"estimating: {fraction:4.0%} {message}".rstrip())

    if tracks.static is not None and opts.use_background:
        report('INFO', f"{tracks.static.n_points} background tracks: the camera from the scene")
    report('INFO', f"estimating with {name!r} on {tracks.n_frames} frames")
    return estimate(tracks, name, focal_mm=opts.focal_mm, height_m=opts.height_m, progress=progress,
                    background=opts.use_background)


def _store_on_scene(scene, tracks, est, truth, report, views=None) -> None:
    from . import scene_data

    scene_data.store_tracks(scene, tracks)
    if views and views[0]:
        scene_data.store_views(scene, views[0], views[1])
    scene_data.store_estimate(scene, est)
    if truth is not None:
        try:
            scene_data.store_truth(scene, truth)
        except RuntimeError as exc:
            report('WARNING', f"truth not stored: {exc}")
    settings = getattr(scene, "monoskel", None)
    if settings is not None and hasattr(settings, "height_m"):
        settings.height_m = est.height_m or settings.height_m


def save_blend(path: str) -> None:
    import bpy

    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(path), check_existing=False)


def run_job(opts: JobOptions, report=_quiet, scene=None) -> JobResult:
    """Do the whole job in the running Blender; see the module docstring."""
    import bpy

    from . import export
    from .review import takes

    validate(opts)
    scene = scene or bpy.context.scene
    tracks, truth = load_input(opts, report)
    views = read_views(opts)
    est = with_background_warning(run_estimate(tracks, truth, opts, report, views), tracks)
    _store_on_scene(scene, tracks, est, truth, report, views)
    if tracks.meta.get("frame_offset"):          # a stretch: it keeps its place on the timeline
        scene.monoskel.tracks_first_frame += int(tracks.meta["frame_offset"])
    report('INFO', "building armature, camera and tracks")
    scene.monoskel.height_m = opts.height_m
    objects = takes.build_take(scene, est, tracks, report=report)
    for warning in (est.diagnostics or {}).get("warnings", []):
        report('WARNING', str(warning))
    clip = footage_clip(opts, scene)
    if clip is not None and objects.get("camera") is not None and int(tracks.meta.get("step", 1) or 1) == 1:
        from .footage_view import set_tracking_focal, show_footage

        show_footage(objects["camera"], clip)
        focal = set_tracking_focal(clip, est)
        report('INFO', f"the camera shows '{clip.name}' behind the armature; its tracking camera: {focal:.1f} mm")
    if opts.target_rig:
        objects["target_rig"] = retarget_job(scene, opts.target_rig, report)
    pictures = review_pictures(clip, est, tracks, report) if opts.review and clip is not None else []
    written: list[str] = []
    try:
        if opts.result:
            write_estimate_json(est, opts.result)
            written.append(opts.result)
        if opts.tracks_out:
            from ..core.tracks import write_tracks_json

            write_tracks_json(tracks, opts.tracks_out)
            written.append(opts.tracks_out)
        if opts.bvh:
            written.append(export.export_bvh(scene, objects["armature"], opts.bvh))
        if opts.fbx:
            written.append(export.export_fbx(scene, [objects["armature"], objects["camera"]], opts.fbx))
        if opts.review:
            written.append(write_review_html(report_path(opts.output), est, title=_report_title(opts, tracks),
                                             fps=tracks.fps, image_size=tracks.image_size,
                                             first_frame=scene.monoskel.tracks_first_frame, pictures=pictures))
        save_blend(opts.output)
        written.append(opts.output)
    except BaseException:
        for path in written:  # all or nothing: no partial set of outputs
            try:
                os.remove(path)
            except OSError:
                pass
        raise
    for path in written:
        report('INFO', f"wrote {path}")
    return JobResult(est, truth, objects, written)


def footage_clip(opts: JobOptions, scene):
    """The Movie Clip of the run's footage (``--video``, or ``--footage`` once it is loaded), else None."""
    if not (opts.video or opts.footage):
        return None
    if scene.active_clip is None and opts.footage:
        from .pose_detection.clip_detect import load_clip

        scene.active_clip = load_clip(opts.footage)
    return scene.active_clip


def review_pictures(clip, est: Estimate, tracks, report=_quiet) -> list:
    """The review page's frames of ``clip`` with the tracks and the solved skeleton drawn on them; none
    (with a warning) when Blender cannot decode them: the page is still written."""
    from .review.footage_frames import clip_pictures

    try:
        step = int(tracks.meta.get("step", 1) or 1)
        first = 1 + step * int(tracks.meta.get("frame_offset", 0) or 0)
        pictures = clip_pictures(clip, est, tracks, first_clip_frame=first, step=step)
    except InputError as exc:
        report('WARNING', f"the review page shows no footage: {exc}")
        return []
    report('INFO', f"review: {len(pictures)} frames of the footage drawn")
    return pictures


def _report_title(opts: JobOptions, tracks) -> str:
    source = opts.input or (f"built-in {opts.builtin}" if opts.builtin else "") or tracks.source or "clip"
    return f"MonoSkel review: {os.path.basename(source)}"


def summary_lines(est: Estimate, truth=None, n_frames: int | None = None) -> list[str]:
    """A short human summary: proportions (against the truth when known), focal length, frames."""
    lines = [f"method: {est.method}   frames: {n_frames if n_frames is not None else len(est.frames)}   "
             f"focal: {est.focal_mm:.1f} mm" + (f"   height: {est.height_m:.2f} m" if est.height_m else "")]
    header = f"{'class':<12} {'proportion':>10}"
    if truth is not None:
        header += f" {'truth':>8} {'error':>8}"
    lines.append(header)
    for i, name in enumerate(CLASSES):
        row = f"{name:<12} {est.proportions[name]:>10.4f}"
        if truth is not None:
            t = float(truth.proportions[i])
            row += f" {t:>8.4f} {100 * (est.proportions[name] - t) / t:>+7.1f}%"
        lines.append(row)
    if est.method == TRUTH_METHOD:
        lines.append("note: built from the generator's ground truth; no estimator ran")
    lens = describe_lens((est.diagnostics or {}).get("lens"))
    if lens:
        lines.append(lens)
    for warning in (est.diagnostics or {}).get("warnings", []):
        lines.append(f"warning: {warning}")
    return lines
