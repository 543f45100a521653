"""``python -m core estimate-multiview VIEW1 VIEW2 [...] --out RESULT.json``: two or more synchronized
views of one person.

Each VIEW is a tracks file (any format ``estimate`` reads).  Cameras come from ``--calibration``
(a ``multiview-calibration`` JSON, one camera per view in order) or, without it, from the person.
The result is a ``skeleton-estimate`` seen through the first view, with every camera in
``diagnostics.cameras``; ``--cameras-out`` also writes them as a calibration file.
"""

from __future__ import annotations

import sys

from ..cli.estimate import _progress, parse_image_size, read_tracks
from ..errors import InputError
from ..io.file_io import check_output_file
from ..result import write_estimate_json


def add_arguments(parser) -> None:
    parser.add_argument("views", nargs="+", metavar="VIEW", help="tracks files, one per camera (2 to 8)")
    parser.add_argument("--out", required=True, metavar="RESULT.json", help="where to write the estimate")
    parser.add_argument("--calibration", default=None, metavar="CAL.json",
                        help="the cameras (multiview-calibration JSON); default: calibrated from the person")
    parser.add_argument("--cameras-out", default=None, metavar="CAL.json",
                        help="also write the cameras used (e.g. the ones calibrated from the person)")
    parser.add_argument("--offsets", default=None, metavar="0,D2,D3",
                        help="per view, the frame that shows the first view's frame 0 (default: found from the joints)")
    parser.add_argument("--height-m", type=float, default=1.75,
                        help="standing height of the person in metres (the scale of self-calibrated cameras)")
    parser.add_argument("--format", default=None, help="input format (default: from each file)")
    parser.add_argument("--fps", type=float, default=None, help="frame rate, for formats that do not store it")
    parser.add_argument("--image-size", default=None, metavar="WxH",
                        help="image size in pixels, for formats that do not store it")


def run(args) -> int:
    from . import estimate_multiview, read_calibration, write_calibration

    check_output_file(args.out)
    if args.cameras_out:
        check_output_file(args.cameras_out, "--cameras-out")
    if len(args.views) < 2:
        raise InputError("estimate-multiview needs at least two views (tracks files)")
    size = parse_image_size(args.image_size)
    views = [read_tracks(p, format=args.format, fps=args.fps, image_size=size) for p in args.views]
    cameras = read_calibration(args.calibration) if args.calibration else None
    offsets = None
    if args.offsets:
        try:
            offsets = [int(v) for v in args.offsets.split(",")]
        except ValueError:
            raise InputError(f"--offsets must be whole frames separated by commas, got {args.offsets!r}") from None
    est = estimate_multiview(views, cameras=cameras, height_m=args.height_m, offsets=offsets, progress=_progress)
    write_estimate_json(est, args.out)
    if args.cameras_out:
        from .cameras import ViewCamera

        write_calibration([ViewCamera.from_dict(c) for c in est.diagnostics["cameras"]], args.cameras_out)
    errs = ", ".join(f"{e:.1f}" for e in est.diagnostics["view_reprojection_px"])
    print(f"cameras: {'given' if cameras else 'calibrated from the person'}; frame offsets "
          f"{est.diagnostics['frame_offsets']}; reprojection per view {errs} px", file=sys.stderr)
    for warning in est.diagnostics.get("warnings", []):
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {args.out} (multiview, {len(views)} views, {len(est.frames)} frames)", file=sys.stderr)
    return 0
