"""``python -m core detect VIDEO_OR_FRAMES --out TRACKS.json``: BlazePose offline, to ``skeleton-tracks``."""

from __future__ import annotations

import os
import sys

from ..errors import InputError
from ..io.file_io import check_output_file
from ..lens.prior import lens_from_file
from ..tracks import write_tracks_json
from .detect import DEFAULT_FPS, detect_frames
from .frames import open_frames
from .tracker import MODES


def add_arguments(parser) -> None:
    parser.add_argument("source", metavar="VIDEO_OR_FRAMES",
                        help="a video file (needs imageio-ffmpeg), a folder of .bmp/.npy frames, or a .npy stack")
    parser.add_argument("--out", required=True, metavar="TRACKS.json", help="where to write the skeleton-tracks JSON")
    parser.add_argument("--fps", type=float, default=None,
                        help=f"frame rate (default: the video's own; {DEFAULT_FPS:g} for image folders)")
    parser.add_argument("--start", type=int, default=0, help="first frame to use, 0-based (default 0)")
    parser.add_argument("--end", type=int, default=None, help="last frame to use, inclusive (default: the last)")
    parser.add_argument("--step", type=int, default=1, help="use every n-th frame (default 1: all)")
    parser.add_argument("--mode", choices=MODES, default="tracking",
                        help="tracking: the last frame's landmarks place the next region, the detector runs only "
                             "when the person is lost (default); per-frame: the detector runs on every frame")
    parser.add_argument("--quiet", action="store_true", help="no progress line")


def _frames(source, start, end):
    for i, frame in enumerate(source.frames(start)):
        if end is not None and start + i > end:
            return
        yield frame


def run(args) -> int:
    check_output_file(args.out)
    if args.start < 0:
        raise InputError(f"--start must be 0 or more, got {args.start}")
    if args.end is not None and args.end < args.start:
        raise InputError(f"--end ({args.end}) is before --start ({args.start})")
    if args.step < 1:
        raise InputError(f"--step must be 1 or more, got {args.step}")
    if args.fps is not None and not args.fps > 0:
        raise InputError(f"--fps must be positive, got {args.fps}")
    source = open_frames(args.source)
    if source.count is not None and args.start >= source.count:
        raise InputError(f"--start {args.start} is past the last frame ({source.count - 1})")
    last = source.count - 1 if source.count is not None else None
    if args.end is not None and last is not None:
        last = min(last, args.end)
    total = None if last is None else (last - args.start) // args.step + 1

    def progress(done, total):
        if not args.quiet and (done % 10 == 0 or done == total):
            of = f"/{total}" if total else ""
            print(f"\rdetecting: frame {done}{of}", end="", file=sys.stderr, flush=True)

    lens = lens_from_file(args.source, (source.width, source.height)) if os.path.isfile(args.source) else None
    try:
        result = detect_frames(_frames(source, args.start, args.end), fps=args.fps or source.fps,
                               image_size=(source.width, source.height), step=args.step, mode=args.mode,
                               first_frame=args.start, total=total, source=args.source, progress=progress,
                               lens=lens)
    finally:
        if not args.quiet:
            print("", file=sys.stderr)
    write_tracks_json(result.tracks, args.out)
    n = len(result.frame_numbers)
    print(f"{args.out}: {n} frames, person in {100 * result.found_share:.0f} %, "
          f"detector ran on {result.detector_runs}, {n / max(result.seconds, 1e-9):.1f} frames/s")
    if lens is not None:
        print(f"lens: {lens.focal_mm:.1f} mm (36 mm film) from {lens.source}; the estimate uses it unless given "
              "--focal-mm")
    for note in result.notes:
        print(f"note: {note}")
    return 0
