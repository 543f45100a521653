"""``python -m core flip-depth RESULT.json --bone l_wrist --frames 120-160 --out FIXED.json``: one bone turned
to its other side in depth over a span of frames (:mod:`core.motion_cleanup.depth_flip`), the picture and
every bone's length kept."""

from __future__ import annotations

import sys

from ..io.file_io import check_output_file
from ..motion_cleanup.depth_flip import flip_depth
from ..result import read_estimate_json, write_estimate_json
from .estimate import parse_frame_range


def add_arguments(parser) -> None:
    parser.add_argument("result", metavar="RESULT.json", help="an estimate with 3D joints (the joint method's)")
    parser.add_argument("--bone", required=True, metavar="JOINT",
                        help="the bone, named by the joint it ends at: l_wrist is the left forearm, l_elbow the left "
                             "upper arm, l_ankle the left shin, l_knee the left thigh (r_... the right ones)")
    parser.add_argument("--frames", required=True, metavar="A-B", help="frames A to B (0-based, inclusive)")
    parser.add_argument("--out", required=True, metavar="FIXED.json", help="where to write the corrected estimate")


def run(args) -> int:
    check_output_file(args.out)
    first, last = parse_frame_range(args.frames)
    est, report = flip_depth(read_estimate_json(args.result), args.bone, first, last)
    write_estimate_json(est, args.out)
    plane = (f"; {report['in_plane']} with the bone in the picture's plane left as they were"
             if report["in_plane"] else "")
    print(f"wrote {args.out}: the bone ending at {args.bone} flipped in depth on {report['frames']} frames of "
          f"{first}-{last}{plane} (largest joint move {100 * report['largest_move_m']:.0f} cm)", file=sys.stderr)
    return 0
