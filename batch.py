"""Headless MonoSkel: tracks (or a motion to film) in, a .blend with armature, camera and motion out.

Runs the same way inside Blender and with the PyPI ``bpy`` module::

    blender -b --python batch.py -- IN --output OUT.blend [options]
    python batch.py IN --output OUT.blend [options]
    python batch.py --builtin walk --output out/demo.blend --result out/demo_result.json

IN is a tracks file (any format the core reads) or a .bvh file, which is
filmed with the virtual camera of the paper's experiment (--kinds, --noise-px,
--dropout, --seed); or ``--video FILE`` (a movie, or the first image of a
sequence) whose person is found by the offline pose detector first::

    python batch.py --video CLIP.mp4 --output scene.blend

A folder of tracks files and videos, N shots at a time, or as a job bundle for a render farm (docs/farm.md)::

    python batch.py --folder SHOTS --output-dir OUT [--workers N] [options for every shot]
    python batch.py --folder SHOTS --output-dir OUT --openjd-bundle BUNDLE

With footage (``--video``, or ``--footage`` beside a tracks file) the background is followed on it
and gives the camera (``--no-background`` leaves it out); the review page beside the .blend shows
frames of the footage with the tracks and the solved skeleton drawn through the solved camera.

The extension is loaded from this working tree, so the code that runs is the
checkout's.  Progress goes to stderr, the summary to
stdout; bad input exits with status 2 and a one-line message, any other
failure with status 1, and in both cases no output file is written.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time


def _script_args(argv: list[str]) -> list[str]:
    """Our arguments: after '--' when present (Blender's convention), else after the script name."""
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    return argv[1:]


class _OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _image_size(text: str):
    try:
        w, h = (float(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"image size must look like 720x480, got {text!r}") from None
    return w, h


def _kinds(text: str):
    return tuple(k.strip() for k in text.split(",") if k.strip())


def make_parser() -> argparse.ArgumentParser:
    p = _OneLineParser(prog="batch.py", description=__doc__.split("\n\n")[0],
                       epilog="Example: python batch.py --builtin walk --output out/demo.blend --result out/r.json")
    p.add_argument("input", nargs="?", help="tracks file (any supported format) or a .bvh motion to film")
    p.add_argument("--builtin", metavar="NAME", help="film a built-in motion instead of IN (walk, run, stand)")
    p.add_argument("--video", metavar="FILE", help="detect the person in this video (or first image of a sequence) "
                                                  "instead of reading tracks; the clip and its joint markers are "
                                                  "kept in OUT")
    p.add_argument("--output", "-o", metavar="OUT.blend", help="the .blend to write (required)")
    p.add_argument("--bvh", metavar="OUT.bvh", help="also export the armature's motion as BVH")
    p.add_argument("--fbx", metavar="OUT.fbx", help="also export armature and camera as FBX")
    p.add_argument("--result", metavar="RESULT.json", help="also write the estimate (skeleton-estimate JSON)")
    p.add_argument("--estimate", metavar="RESULT.json", help="build this existing estimate instead of estimating")
    p.add_argument("--method", help="estimator (default: the best available); 'truth' builds the generator's truth")
    p.add_argument("--focal-mm", type=float, help="focal length hint in 36 mm film millimetres")
    p.add_argument("--height-m", type=float, default=1.75, help="subject height in metres (default 1.75)")
    p.add_argument("--target-rig", metavar="FILE.blend:ARMATURE",
                   help="also retarget the motion onto this armature from another .blend (its stored bone "
                        "map, or one guessed from Rigify, Mixamo or Unreal names); its action is saved in OUT")
    p.add_argument("--views", nargs="+", default=(), metavar="VIEW",
                   help="further synchronized views of the same person (tracks files): estimate from all of them "
                        "(the input is the first view; one camera object per view)")
    p.add_argument("--calibration", metavar="CAL.json",
                   help="the views' cameras (multiview-calibration JSON); default: calibrated from the person")
    p.add_argument("--no-report", dest="review", action="store_false",
                   help="do not write the review report (OUT.review.html: residual and camera plots, "
                        "proportions, warnings) beside the .blend")
    p.add_argument("--track-background", action="store_true",
                   help="(the default whenever there is footage) find and follow static background features "
                        "on the footage (--video, or --footage) with Blender's tracker, so the camera comes "
                        "from the scene; a scene that gives too little falls back to the person, with a warning")
    p.add_argument("--no-background", dest="use_background", action="store_false",
                   help="neither follow the footage's background nor use the tracks' static background points "
                        "(the camera from the person alone)")
    g = p.add_argument_group("motion input (.bvh or --builtin): the paper's experiment")
    g.add_argument("--kinds", type=_kinds, default=("pan", "tilt", "zoom"),
                   help="camera moves, comma separated (default pan,tilt,zoom)")
    g.add_argument("--noise-px", type=float, default=1.0, help="2D noise, pixels (default 1)")
    g.add_argument("--dropout", type=float, default=0.0, help="fraction of joints dropped (default 0)")
    g.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    g.add_argument("--frames", type=int, dest="max_frames", help="use at most this many frames")
    g.add_argument("--static-points", type=int, default=0,
                   help="also film this many static background points (floor, wall) for the camera (default 0)")
    d = p.add_argument_group("video input (--video): the pose detector")
    d.add_argument("--detect-mode", default="tracking", choices=("tracking", "per-frame"),
                   help="tracking: the detector runs only when the person is lost (default); per-frame: every frame")
    d.add_argument("--detect-step", type=int, default=1, help="detect on every n-th frame (default 1)")
    d.add_argument("--tracks-out", metavar="TRACKS.json", help="also write the detected tracks")
    t = p.add_argument_group("tracks input")
    t.add_argument("--format", help="tracks format when the file name does not say")
    t.add_argument("--fps", type=float, help="frame rate when the file lacks it")
    t.add_argument("--image-size", type=_image_size, help="WxH pixels when the file lacks it")
    t.add_argument("--min-confidence", type=float, default=0.0, help="treat joints below this as missing")
    t.add_argument("--footage", metavar="FILE", help="the video (or first image of a sequence) the tracks were "
                                                     "made from: its background is followed for the camera")
    t.add_argument("--frame-range", metavar="A-B",
                   help="only the tracks' frames A to B (0-based, inclusive; tracks files and --video), e.g. the "
                        "stretch of one person that the self-check names; the build keeps their place in time")
    _folder_cli().add_folder_arguments(p)
    return p


def _folder_cli():
    """This checkout's ``core.shots.folder_cli``: many shots (--folder), in parallel or as a farm job bundle."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import extension_loader

    extension_loader.load_extension()
    from monoskel.core.shots import folder_cli

    return folder_cli


def _report(level: str, message: str) -> None:
    print(f"[monoskel] {level}: {message}", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    parser, our_args = make_parser(), _script_args(sys.argv if argv is None else argv)
    args = parser.parse_args(our_args)
    if _folder_cli().wanted(args):  # bpy is in sys.modules before this script runs only inside Blender
        return _folder_cli().run_folder(args, our_args, parser, os.path.abspath(__file__), sys.modules.get("bpy"))
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import extension_loader

    started = time.perf_counter()
    extension_loader.load_extension()  # the checkout's code; importing it does not start Blender
    from monoskel.blender.worker import JobOptions, run_job, summary_lines, validate
    from monoskel.core.errors import InputError

    opts = JobOptions(output=args.output, input=args.input, builtin=args.builtin, estimate=args.estimate,
                      bvh=args.bvh, fbx=args.fbx, result=args.result, method=args.method, focal_mm=args.focal_mm,
                      height_m=args.height_m, kinds=args.kinds, noise_px=args.noise_px, dropout=args.dropout,
                      seed=args.seed, max_frames=args.max_frames, format=args.format, fps=args.fps,
                      image_size=args.image_size, min_confidence=args.min_confidence,
                      static_points=args.static_points, use_background=args.use_background,
                      review=args.review, target_rig=args.target_rig, views=tuple(args.views),
                      calibration=args.calibration, video=args.video, detect_mode=args.detect_mode,
                      detect_step=args.detect_step, tracks_out=args.tracks_out, frame_range=args.frame_range,
                      track_background=args.track_background, footage=args.footage)
    try:
        validate(opts)  # before Blender starts: bad arguments fail fast
    except InputError as exc:
        print(f"batch.py: error: {exc}", file=sys.stderr)
        return 2
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = sys.modules["monoskel"]
    addon.register()
    try:
        with contextlib.redirect_stdout(sys.stderr):  # Blender's exporters print progress; keep stdout the summary
            result = run_job(opts, _report)
    except InputError as exc:
        print(f"batch.py: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # a bug or a Blender failure: still one line, still no output file
        print(f"batch.py: failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        if os.environ.get("MONOSKEL_TRACEBACK"):
            raise
        return 1
    finally:
        # bpy 4.2 as a Python module crashes at interpreter exit while add-on classes are registered.
        addon.unregister()
    for line in summary_lines(result.estimate, result.truth):
        print(line)
    print(f"wrote {', '.join(result.written)} in {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.exit(code)
