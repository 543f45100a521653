"""``python -m core estimate TRACKS --out RESULT.json``: run an estimator on a tracks file.

Reads any supported format (through :func:`core.io.formats.read_any` when present,
otherwise the native ``skeleton-tracks`` JSON), runs :func:`core.estimate.estimate`
and writes the ``skeleton-estimate`` JSON atomically, so a failure leaves no
RESULT file behind.  Progress goes to stderr.
"""

from __future__ import annotations

import sys

from ..errors import InputError
from ..estimate import METHODS, estimate
from ..io.file_io import check_output_file
from ..lens.prior import describe as describe_lens
from ..result import write_estimate_json


def add_arguments(parser) -> None:
    parser.add_argument("tracks", metavar="TRACKS", help="2D joint tracks (skeleton-tracks JSON or another format)")
    parser.add_argument("--out", required=True, metavar="RESULT.json", help="where to write the estimate")
    parser.add_argument("--focal-mm", type=float, default=None,
                        help="focal length of frame 0, 36 mm film equivalent (default: the lens the footage recorded, "
                             "kept in the tracks by 'detect', else 50 mm or the method's own)")
    parser.add_argument("--method", default=None, choices=sorted(METHODS),
                        help="estimator (default: the best the project has)")
    parser.add_argument("--height-m", type=float, default=1.75, help="standing height of the person in metres")
    parser.add_argument("--format", default=None, help="input format (default: from the file)")
    parser.add_argument("--fps", type=float, default=None, help="frame rate, for formats that do not store it")
    parser.add_argument("--image-size", default=None, metavar="WxH",
                        help="image size in pixels, for formats that do not store it")
    parser.add_argument("--frames", default=None, metavar="A-B",
                        help="estimate only frames A to B (0-based, inclusive), e.g. one person's stretch that the "
                             "self-check named; the result holds those frames")
    parser.add_argument("--no-background", dest="use_background", action="store_false",
                        help="ignore the tracks' static background points (the camera from the person alone)")
    parser.add_argument("--no-foot-lock", dest="foot_lock", action="store_false",
                        help="keep the solved motion as it is: no planted feet held still (core.motion_cleanup)")


def parse_frame_range(text: str | None, flag: str = "--frames") -> tuple[int, int] | None:
    """``"120-540"`` -> (120, 540); None for None. ``flag`` names the option in the error."""
    if text is None:
        return None
    first, sep, last = text.partition("-")
    try:
        a, b = int(first), int(last)
    except ValueError:
        raise InputError(f"{flag} must look like 120-540 (first-last, 0-based), got {text!r}") from None
    if not sep or a < 0 or b < a:
        raise InputError(f"{flag} must look like 120-540 (first-last, 0-based, first <= last), got {text!r}")
    return a, b


def parse_image_size(text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        w, h = (float(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--image-size must look like 720x480, got {text!r}") from None
    if not (w > 0 and h > 0):
        raise InputError(f"--image-size must be positive, got {text!r}")
    return (w, h)


def read_tracks(path: str, *, format: str | None = None, fps: float | None = None,
                image_size: tuple[float, float] | None = None):
    """Tracks from ``path`` in any format the project can read."""
    try:
        from ..io.formats import read_any
    except ImportError:
        read_any = None
    if read_any is not None:
        return read_any(path, format=format, fps=fps, image_size=image_size)
    if format not in (None, "skeleton-tracks", "native", "json"):
        raise InputError(f"{path}: unknown format {format!r} (only skeleton-tracks JSON is available)")
    from ..tracks import read_tracks_json

    return read_tracks_json(path)


def _progress(fraction: float, message: str) -> None:
    print(f"[{fraction * 100:5.1f}%] {message}", file=sys.stderr, flush=True)


def run(args) -> int:
    check_output_file(args.out)
    image_size = parse_image_size(args.image_size)
    if args.fps is not None and not (args.fps > 0):
        raise InputError(f"--fps must be positive, got {args.fps}")
    span = parse_frame_range(args.frames)
    tracks = read_tracks(args.tracks, format=args.format, fps=args.fps, image_size=image_size)
    if span is not None:
        tracks = tracks.frames_between(*span)
    est = estimate(tracks, args.method, focal_mm=args.focal_mm, height_m=args.height_m, progress=_progress,
                   background=args.use_background, **({} if args.foot_lock else {"motion_cleanup": None}))
    write_estimate_json(est, args.out)
    scene = (est.diagnostics or {}).get("scene_camera")
    if scene and scene.get("used"):
        print(f"camera: from {scene['points_used']} background points, turning {scene['turn_deg']:.0f} degrees, "
              f"focal length {'determined' if scene['focal_determined'] else 'not determined'} "
              f"({est.focal_mm:.1f} mm)", file=sys.stderr)
    cleaning = (est.diagnostics or {}).get("cleaning")
    if cleaning:
        unexplained = cleaning.get("unexplained", 0)
        print(f"input: {cleaning['outliers'] + cleaning['outside_image']} of {cleaning['observed_points']} joint "
              f"points rejected, left/right undone in {cleaning['swapped_frames']} frames"
              + (f"; solved again without {unexplained} points the first answer could not explain"
                 if unexplained else ""), file=sys.stderr)
    lens = describe_lens((est.diagnostics or {}).get("lens"))
    if lens:
        print(lens, file=sys.stderr)
    for warning in (est.diagnostics or {}).get("warnings", []):
        print(f"warning: {warning}", file=sys.stderr)
    span_note = f" {span[0]}-{span[1]}" if span is not None else ""
    print(f"wrote {args.out} ({est.method}, {len(est.frames)} frames{span_note})", file=sys.stderr)
    return 0
