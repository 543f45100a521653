"""``python -m core synth``: synthetic 2D tracks + ground truth from a BVH or built-in motion.

Number options are parsed here rather than by argparse so that every bad
value is one ``InputError`` line (exit 2) and nothing is written: both files
are produced in memory first, then written atomically; if the second write
fails, the first file is removed again.
"""

from __future__ import annotations

import math
import os

from ..errors import InputError
from ..io.file_io import check_output_file
from ..synthetic.footage_sim import DetectorErrors, HandheldOperator
from ..synthetic.footage_sim.detector import TYPICAL
from ..synthetic.synth_camera import CAMERA_KINDS, check_kinds


def add_arguments(parser) -> None:
    parser.add_argument("source", nargs="?", metavar="BVH", help="BVH motion file (or use --builtin)")
    parser.add_argument("--builtin", metavar="NAME", help="built-in procedural motion instead of a BVH (e.g. walk)")
    parser.add_argument("--out", required=True, metavar="TRACKS.json", help="tracks file to write (skeleton-tracks)")
    parser.add_argument("--truth", required=True, metavar="TRUTH.json", help="ground-truth file to write")
    parser.add_argument("--kinds", default="pan,tilt,zoom",
                        help=f"camera motions, comma-separated, from {','.join(CAMERA_KINDS)} (default pan,tilt,zoom)")
    parser.add_argument("--continuous", action="store_true", help="no still spells between camera motions")
    parser.add_argument("--noise-px", default="1", help="Gaussian noise per pixel coordinate (default 1)")
    parser.add_argument("--dropout", default="0", help="fraction of joint observations dropped at random (default 0)")
    parser.add_argument("--occlusion-s", default="0", help="seconds a random limb is hidden, per event (default 0)")
    parser.add_argument("--focal-mm", default="50", help="frame-0 focal length, 36 mm film equivalent (default 50)")
    parser.add_argument("--image-size", default="720x480", help="WIDTHxHEIGHT in pixels (default 720x480)")
    parser.add_argument("--fps", default=None, help="resample the motion to this frame rate (default: keep)")
    parser.add_argument("--max-frames", default=None, help="use at most this many frames (after resampling)")
    parser.add_argument("--height-m", default="1.75", help="standing height of the figure in metres (default 1.75)")
    parser.add_argument("--view-offset-deg", default=None,
                        help="turn the view this far from the side view of the path (default: automatic)")
    parser.add_argument("--seed", default="0", help="random seed for schedule, noise and drop-outs (default 0)")
    parser.add_argument("--operator", default="tripod", choices=["tripod", "handheld"],
                        help="tripod: the paper's still spells and single moves (default); handheld: overlapping "
                             "random pans, tilts and zooms with hand shake, no still spell promised")
    parser.add_argument("--static-points", default="0",
                        help="static scene points to track besides the person: half on the floor around them, "
                             "half on a wall beyond, each seen while inside the picture (default 0)")
    parser.add_argument("--operator-walk", default="0",
                        help="handheld: the operator walks sideways at this speed, m/s - a camera that translates, "
                             "which the estimators do not model (default 0)")
    parser.add_argument("--shake-deg", default="0.15", help="handheld shake, degrees per axis (default 0.15)")
    parser.add_argument("--outliers", default=None,
                        help="detector: share of joint entries thrown to a random image point for 1-3 frames")
    parser.add_argument("--swaps", default=None,
                        help="detector: share of frames with left/right limbs (or the whole body) exchanged, "
                             "1-8 frames")
    parser.add_argument("--missing-runs", default=None,
                        help="detector: share of joint entries missing in runs of 0.2-1 s")
    parser.add_argument("--missing-as-measured", action="store_true",
                        help="detector: joints go missing where and as long as BlazePose lost them on real "
                             "footage (mostly the arms, runs up to 4 s; docs/pose_detection.md)")
    parser.add_argument("--extremity-jitter", action="store_true",
                        help="detector: noise x2 at wrists and ankles, x1.5 at elbows and knees")
    parser.add_argument("--confidence", action="store_true",
                        help="detector: confidence falls with the error (outliers 0.05-0.6) instead of 1.0")
    parser.add_argument("--detector-errors", action="store_true",
                        help="the typical mix: 1%% outliers, 5%% swapped frames, 1%% missing runs, extremity "
                             "jitter and confidence (the single options above override its parts)")


def _number(option: str, text, *, positive: bool = False, upper: float | None = None) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{option} must be a number, got {text!r}") from None
    if not math.isfinite(value) or value < 0 or (positive and value == 0):
        kind = "a positive" if positive else "a non-negative"
        raise InputError(f"{option} must be {kind} number, got {text!r}")
    if upper is not None and value >= upper:
        raise InputError(f"{option} must be below {upper:g}, got {text!r}")
    return value


def _integer(option: str, text, *, minimum: int) -> int:
    try:
        value = int(str(text), 10)
    except (TypeError, ValueError):
        raise InputError(f"{option} must be an integer, got {text!r}") from None
    if value < minimum:
        raise InputError(f"{option} must be at least {minimum}, got {text!r}")
    return value


def _image_size(text: str) -> tuple[int, int]:
    parts = str(text).lower().split("x")
    try:
        w, h = (int(p, 10) for p in parts)
    except ValueError:
        raise InputError(f"--image-size must look like 720x480, got {text!r}") from None
    if w < 16 or h < 16:
        raise InputError(f"--image-size must be at least 16x16 pixels, got {text!r}")
    return w, h


def _describe(d: DetectorErrors) -> str:
    parts = [f"{k} {v:g}" for k, v in (("outliers", d.outliers), ("swaps", d.swaps),
                                         ("missing runs", d.missing_runs)) if v]
    parts += [k for k, v in (("extremity jitter", d.extremity_jitter), ("confidence", d.confidence),
                             ("missing as measured", d.missing_as_measured)) if v]
    return ", ".join(parts) or "none"


def run(args) -> int:
    from ..synthetic.motion import BUILTIN_PREFIX, load_motion
    from ..synthetic.synth import synthesize
    from ..synthetic.truth import write_truth_json
    from ..tracks import write_tracks_json

    if (args.source is None) == (args.builtin is None):
        raise InputError("give exactly one motion: a BVH file or --builtin NAME")
    if args.source is not None:
        if not os.path.isfile(args.source):
            raise InputError(f"{args.source}: no such BVH file")
        source = args.source
    else:
        source = BUILTIN_PREFIX + args.builtin
    kinds = check_kinds(args.kinds)
    noise = _number("--noise-px", args.noise_px)
    dropout = _number("--dropout", args.dropout, upper=1.0)
    occlusion = _number("--occlusion-s", args.occlusion_s)
    focal = _number("--focal-mm", args.focal_mm, positive=True)
    size = _image_size(args.image_size)
    fps = None if args.fps is None else _number("--fps", args.fps, positive=True)
    max_frames = None if args.max_frames is None else _integer("--max-frames", args.max_frames, minimum=2)
    height = _number("--height-m", args.height_m, positive=True)
    seed = _integer("--seed", args.seed, minimum=0)
    view = None
    if args.view_offset_deg is not None:
        try:
            view = float(args.view_offset_deg)
        except ValueError:
            view = math.nan
        if not (math.isfinite(view) and -90.0 < view < 90.0):
            raise InputError(f"--view-offset-deg must be a number of degrees between -90 and 90, "
                             f"got {args.view_offset_deg!r}")
    out = check_output_file(args.out, "--out")
    truth_path = check_output_file(args.truth, "--truth")
    if os.path.abspath(out) == os.path.abspath(truth_path):
        raise InputError("--out and --truth must be different files")

    operator = None
    if args.operator != "handheld" and _number("--operator-walk", args.operator_walk, upper=5.0) > 0:
        raise InputError("--operator-walk needs --operator handheld")
    if args.operator == "handheld":
        operator = HandheldOperator(shake_deg=_number("--shake-deg", args.shake_deg),
                                    walk_m_s=_number("--operator-walk", args.operator_walk, upper=5.0))
    base = TYPICAL if args.detector_errors else DetectorErrors()

    def rate(option: str, given, default: float) -> float:
        """A detector rate given on the command line (0 included), else the mix's default."""
        return default if given is None else _number(option, given, upper=0.5)

    detector = DetectorErrors(
        outliers=rate("--outliers", args.outliers, base.outliers),
        swaps=rate("--swaps", args.swaps, base.swaps),
        missing_runs=rate("--missing-runs", args.missing_runs, base.missing_runs),
        extremity_jitter=bool(args.extremity_jitter or base.extremity_jitter),
        confidence=bool(args.confidence or base.confidence),
        missing_as_measured=bool(args.missing_as_measured))

    static_points = _number("--static-points", args.static_points, upper=1000)
    if static_points != int(static_points):
        raise InputError(f"--static-points must be a whole number, got {args.static_points!r}")
    motion = load_motion(source, height_m=height, max_frames=max_frames, fps=fps)
    tracks, truth = synthesize(motion, kinds=kinds, focal_mm=focal, image_size=size, noise_px=noise,
                               dropout=dropout, occlusion_s=occlusion, seed=seed, continuous=args.continuous,
                               view_offset_deg=view, operator=operator, detector=detector,
                               static_points=int(static_points))
    try:
        write_tracks_json(tracks, out)
    except OSError as exc:
        raise InputError(f"{out}: cannot write tracks file ({exc.strerror or exc})") from None
    try:
        write_truth_json(truth, truth_path)
    except InputError:
        os.remove(out)
        raise

    moving = [s for s in truth.spells if s.moving]
    kinds_seen = ", ".join(f"{s.kind} {s.start}-{s.end}" for s in moving) or "none"
    print(f"{motion.name}: {tracks.n_frames} frames at {tracks.fps:g} fps, {int(size[0])}x{int(size[1])}, "
          f"camera {truth.generator['camera_distance_m']:.1f} m away (view turned "
          f"{truth.generator['view_offset_deg']:+.0f} deg), focal {focal:g} mm; {len(truth.spells)} spells "
          f"({len(moving)} moving: {kinds_seen}); {100.0 * (1.0 - tracks.missing_fraction()):.1f}% of joints "
          f"visible; noise {noise:g} px, drop-out {dropout:g}, occlusion {occlusion:g} s, "
          f"{args.operator} operator, detector errors {_describe(detector)}, "
          f"{int(static_points)} static points, seed {seed}; "
          f"wrote {out} and {truth_path}.")
    return 0
