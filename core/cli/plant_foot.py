"""``python -m core plant-foot RESULT.json --foot l --frames 120-140 --out FIXED.json``: one foot held still in the
world over a span of frames (:mod:`core.motion_cleanup.foot_plant`), the leg bent to reach it."""

from __future__ import annotations

import sys

from ..io.file_io import check_output_file
from ..motion_cleanup.foot_plant import REACH_WARN_M, SIDE_NAMES, plant_foot, reach_warning, stance_span
from ..result import read_estimate_json, write_estimate_json
from .estimate import parse_frame_range


def add_arguments(parser) -> None:
    parser.add_argument("result", metavar="RESULT.json", help="an estimate with 3D joints (the joint method's)")
    parser.add_argument("--foot", required=True, choices=["l", "r"], help="the left (l) or right (r) foot")
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--frames", metavar="A-B", help="frames A to B (0-based, inclusive)")
    where.add_argument("--at", type=int, metavar="F",
                       help="the frames around frame F on which the solve names that foot the standing one "
                            "(a start: check them against the footage)")
    parser.add_argument("--out", required=True, metavar="FIXED.json", help="where to write the corrected estimate")


def run(args) -> int:
    check_output_file(args.out)
    est = read_estimate_json(args.result)
    first, last = parse_frame_range(args.frames) if args.frames is not None else stance_span(est, args.foot, args.at)
    fixed, report = plant_foot(est, args.foot, first, last)
    write_estimate_json(fixed, args.out)
    body = (f"; the body slid back up to {100 * report['body_slide_m']:.0f} cm along its line of sight to reach it"
            if report["body_slide_m"] > 0 else "")
    print(f"wrote {args.out}: the {SIDE_NAMES[args.foot]} foot held still on frames {first}-{last} (it had strayed "
          f"up to {100 * report['slide_m']:.0f} cm; largest ankle move {100 * report['largest_move_m']:.0f} cm{body})",
          file=sys.stderr)
    if report["unreached_m"] > REACH_WARN_M:
        print(f"warning: {reach_warning(report)}", file=sys.stderr)
    return 0
