"""``python -m core single-image TRACKS --frame N --out POSE.json``: one frame's 3D pose (Taylor 2000)."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import InputError
from ..io.file_io import check_output_file
from ..skeleton import CLASSES
from .pose import SEGMENT_NAMES, parse_constraints, parse_signs, pose_from_image, write_pose_json


def add_arguments(parser) -> None:
    parser.add_argument("tracks", metavar="TRACKS", help="2D joint tracks in any supported format (one frame is used)")
    parser.add_argument("--frame", type=int, default=0, help="frame to pose, 0-based (default 0)")
    parser.add_argument("--out", required=True, metavar="POSE.json", help="where to write the skeleton-pose JSON")
    parser.add_argument("--proportions", metavar="RESULT.json",
                        help="segment lengths from an estimate (default: the built-in adult figure)")
    parser.add_argument("--lengths", metavar="CLASS=M,...",
                        help="class lengths in metres, e.g. thigh=0.45,shank=0.42 (override the others)")
    parser.add_argument("--height-m", type=float, default=1.75, help="standing height in metres (default 1.75)")
    parser.add_argument("--focal-mm", type=float, default=None,
                        help="focal length (36 mm film): pose under perspective with it")
    parser.add_argument("--perspective", action="store_true",
                        help="perspective with the focal length assumed (50 mm) when not given")
    parser.add_argument("--no-refine", dest="refine", action="store_false",
                        help="under perspective, keep Taylor's construction as it is (no least-squares polish)")
    parser.add_argument("--scale", default=None,
                        help="Taylor's scale: pixels per metre, 'min' (the smallest that fits every segment) or "
                             "'trunk' (from pelvis to neck; the default without constraints)")
    parser.add_argument("--signs", default=None, metavar="SEG=+|-,...",
                        help=f"depth signs to hold (+: child farther than parent), segments {', '.join(SEGMENT_NAMES)}")
    parser.add_argument("--closure", action="append", default=[], metavar="JOINT=JOINT",
                        help="two joints that coincide (e.g. l_wrist=r_wrist); repeatable")
    parser.add_argument("--coplanar", action="append", default=[], metavar="J1,J2,J3,J4",
                        help="four joints on one plane; repeatable")
    parser.add_argument("--format", default=None, help="tracks format (default: from the file)")
    parser.add_argument("--fps", type=float, default=None, help="frame rate, for formats that do not store it")
    parser.add_argument("--image-size", default=None, metavar="WxH", help="image size, for formats that lack it")


def class_lengths(args) -> np.ndarray:
    """(10,) metres from --proportions / the adult figure, --height-m and --lengths."""
    from ..skeleton import class_lengths_for_height
    from ..synthetic.procedural import adult_class_lengths

    if not (args.height_m and 0.3 <= args.height_m <= 3.0):
        raise InputError(f"--height-m must be between 0.3 and 3, got {args.height_m}")
    if args.proportions:
        from ..result import read_estimate_json

        est = read_estimate_json(args.proportions)
        lengths = class_lengths_for_height(est.proportions_vector(), args.height_m)
    else:
        lengths = adult_class_lengths(args.height_m)
    for part in (p.strip() for p in (args.lengths or "").split(",") if p.strip()):
        name, sep, value = part.partition("=")
        try:
            v = float(value)
        except ValueError:
            v = float("nan")
        if not sep or name.strip() not in CLASSES or not (np.isfinite(v) and v > 0):
            raise InputError(f"--lengths: {part!r} must be CLASS=METRES with a class from {list(CLASSES)}")
        lengths[CLASSES.index(name.strip())] = v
    return lengths


def run(args) -> int:
    from ..cli.estimate import parse_image_size, read_tracks

    check_output_file(args.out)
    tracks = read_tracks(args.tracks, format=args.format, fps=args.fps, image_size=parse_image_size(args.image_size))
    if not 0 <= args.frame < tracks.n_frames:
        raise InputError(f"--frame {args.frame} is outside the tracks (0-{tracks.n_frames - 1})")
    if args.focal_mm is not None and not (args.focal_mm > 0):
        raise InputError(f"--focal-mm must be positive, got {args.focal_mm}")
    scale = args.scale
    if scale not in (None, "min", "trunk"):
        try:
            scale = float(scale)
        except ValueError:
            raise InputError(f"--scale must be a number, 'min' or 'trunk', got {scale!r}") from None
    pose = pose_from_image(tracks.xy[args.frame], tracks.image_size, class_lengths(args), focal_mm=args.focal_mm,
                           perspective=args.perspective, scale=scale, signs=parse_signs(args.signs), refine=args.refine,
                           constraints=parse_constraints(args.closure, args.coplanar))
    write_pose_json(pose, tracks.image_size, args.out, source=f"{tracks.source} frame {args.frame}")
    amb = ", ".join(SEGMENT_NAMES[k] for k in pose.ambiguous) or "none"
    print(f"posed frame {args.frame} ({pose.projection}): scale {pose.scale:.1f} px/m (minimum {pose.scale_min:.1f}); "
          f"ambiguous segments: {amb}; wrote {args.out}", file=sys.stderr)
    return 0
