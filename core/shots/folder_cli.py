"""``batch.py --folder SHOTS --output-dir OUT``: every shot of a folder, N at a time; or a farm job bundle.

``batch.py`` adds these options (:func:`add_folder_arguments`) and hands over to :func:`run_folder` when
one is given.  The single-shot options the user gives apply to every shot; the options that name one
shot's input or files are refused, since each shot's files go to ``OUT/<shot>/``.
"""

from __future__ import annotations

import os
import shlex
import sys

from ..errors import InputError
from .command import absolute_rig_spec, current_runner, given_options, option_arguments, shot_arguments
from .discover import discover_shots, find_shot
from .index_page import BUILT, UP_TO_DATE, result_figures, write_index
from .openjd import job_template, write_bundle
from .outputs import FAILED, OK, expected_files, shot_outputs, up_to_date
from .runner import ShotJob, ShotRunner, default_workers

#: The folder run's own options (never passed on to a shot).
FOLDER_DESTS = ("folder", "output_dir", "workers", "force", "shot", "index_only", "openjd_bundle", "print_tasks",
                "exports")
#: Single-shot options that name one shot's input or output files.
PER_SHOT = {"input": "IN", "builtin": "--builtin", "video": "--video", "output": "--output", "result": "--result",
            "estimate": "--estimate", "bvh": "--bvh", "fbx": "--fbx", "tracks_out": "--tracks-out",
            "footage": "--footage", "views": "--views", "calibration": "--calibration",
            "frame_range": "--frame-range"}
EXPORTS = ("bvh", "fbx")


def _exports(text: str) -> tuple[str, ...]:
    import argparse

    found = tuple(dict.fromkeys(e.strip().lower() for e in text.split(",") if e.strip()))
    bad = [e for e in found if e not in EXPORTS]
    if bad:
        raise argparse.ArgumentTypeError(f"--exports takes {', '.join(EXPORTS)}, got {', '.join(bad)}")
    return found


def add_folder_arguments(parser) -> None:
    g = parser.add_argument_group(
        "many shots (--folder)",
        "build every tracks file (.json, .csv, OpenPose folder) and video in SHOTS, each in its own process, "
        "into OUT/<shot>/ with OUT/index.html listing them all; the options above apply to every shot")
    g.add_argument("--folder", metavar="SHOTS", help="the folder of shots")
    g.add_argument("--output-dir", metavar="OUT", help="where each shot's folder and index.html go")
    g.add_argument("--workers", type=int, metavar="N", help="shots built at once (default: the cores)")
    g.add_argument("--force", action="store_true", help="build every shot again, even those up to date")
    g.add_argument("--exports", type=_exports, default=(), metavar="bvh,fbx",
                   help="also export each shot's motion as OUT/<shot>/<shot>.bvh and/or .fbx")
    g.add_argument("--shot", metavar="NAME", help="build only this shot (one farm task); the index is not written")
    g.add_argument("--index-only", action="store_true", help="only write OUT/index.html from what OUT holds")
    g.add_argument("--openjd-bundle", metavar="DIR",
                   help="write an Open Job Description job bundle (one task per shot) to DIR instead of running")
    g.add_argument("--print-tasks", action="store_true",
                   help="print the farm tasks instead of running: one command line per shot, then the index's")


def wanted(args) -> bool:
    """True when ``args`` ask for the folder run."""
    return any(getattr(args, d, None) not in (None, False, ()) for d in FOLDER_DESTS)


def _check(args, given: dict) -> None:
    if not args.folder:
        raise InputError("--output-dir, --workers, --force, --exports, --shot, --index-only, --openjd-bundle and "
                         "--print-tasks go with --folder SHOTS")
    if not args.output_dir:
        raise InputError("--folder needs --output-dir OUT (each shot goes to OUT/<shot>/)")
    for dest, name in PER_SHOT.items():
        if dest in given:
            raise InputError(f"{name} names one shot's input or file; with --folder every shot is an input and its "
                             "files go to OUT/<shot>/" + (" (use --exports bvh,fbx)" if dest in EXPORTS else ""))
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers must be 1 or more, got {args.workers}")
    if (args.openjd_bundle or args.print_tasks) and (args.shot or args.index_only):
        raise InputError("--openjd-bundle and --print-tasks give the whole folder's job: not with --shot or "
                         "--index-only")
    if args.shot and args.index_only:
        raise InputError("--shot builds one shot, --index-only builds none: give one of them")


def shared_arguments(parser, argv: list[str]) -> tuple[list[str], dict]:
    """The single-shot options of ``argv`` that every shot gets, and every option given (see given_options)."""
    given = given_options(parser, argv)
    if "target_rig" in given:
        option, values = given["target_rig"]
        given["target_rig"] = (option, [absolute_rig_spec(values[0])])
    keep = {d for d in given if d not in FOLDER_DESTS and d not in PER_SHOT}
    return option_arguments(given, keep), given


def task_commands(names: list[str], runner, batch_script: str, shots_dir: str, out_dir: str,
                  shared: list[str]) -> list[str]:
    """The farm tasks as shell command lines: one per shot (``--shot NAME``), then the index's, which must
    run after them all.  Each shot's task writes only into OUT/<shot>/."""
    head = ["--folder", os.path.abspath(shots_dir), "--output-dir", os.path.abspath(out_dir)]
    script = os.path.abspath(batch_script)
    lines = [runner.command(script, [*head, "--shot", name, *shared]) for name in names]
    lines.append(runner.command(script, [*head, "--index-only"]))
    return [shlex.join(cmd) for cmd in lines]


def _title(folder: str) -> str:
    return f"MonoSkel shots: {os.path.basename(os.path.abspath(folder))}"


def _say(line: str) -> None:
    print(line, flush=True)


def _progress_line(result, done: int, total: int, out_dir: str, shot) -> str:
    head = f"[{done}/{total}] {result.name}:"
    if result.status == FAILED:
        return f"{head} FAILED after {result.seconds:.1f} s: {result.error}"
    figures = result_figures(shot_outputs(out_dir, shot).result)
    said = f"{figures.get('frames', '?')} frames"
    if figures.get("warnings"):
        said += f", {len(figures['warnings'])} warning{'s' * (len(figures['warnings']) != 1)}"
    return f"{head} built in {result.seconds:.1f} s ({said})"


def run_folder(args, argv: list[str], parser, batch_script: str, blender_module=None) -> int:
    """The folder run; the exit status: 0 all shots built, 1 a shot failed, 2 bad arguments."""
    try:
        shared, given = shared_arguments(parser, argv)
        _check(args, given)
        shots = [find_shot(args.folder, args.shot)] if args.shot else discover_shots(args.folder)
        if not shots:
            raise InputError(f"{args.folder}: no tracks files (.json, .csv) or videos found")
        out_dir = os.path.abspath(args.output_dir)
        runner = current_runner(blender_module)
        if args.print_tasks:
            for line in task_commands([s.name for s in shots], runner, batch_script, args.folder, out_dir, shared):
                _say(line)
            return 0
        if args.openjd_bundle:
            template = job_template([s.name for s in shots], runner, batch_script, args.folder, out_dir, shared,
                                    job_name=f"MonoSkel {os.path.basename(os.path.abspath(args.folder))}")
            written = write_bundle(args.openjd_bundle, template, "MonoSkel batch.py --openjd-bundle")
            _say(f"wrote {', '.join(written)}: {len(shots)} shot task{'s' * (len(shots) != 1)}, then the index")
            _say(f"run it here: openjd run {written[0]}    on AWS Deadline Cloud: deadline bundle submit "
                 f"{args.openjd_bundle}")
            return 0
        os.makedirs(out_dir, exist_ok=True)
    except InputError as exc:
        print(f"batch.py: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"batch.py: error: {args.output_dir}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    if args.index_only:
        rows = write_index(out_dir, shots, title=_title(args.folder))
        bad = [r["shot"] for r in rows if r["status"] != OK]
        _say(f"wrote {os.path.join(out_dir, 'index.html')}: {len(rows) - len(bad)} of {len(rows)} shots built"
             + (f"; not built: {', '.join(bad)}" if bad else ""))
        return 1 if bad else 0

    jobs, this_run = [], {}
    for shot in shots:
        outs = shot_outputs(out_dir, shot)
        args_ = shot_arguments(shot, outs, shared, track_background=args.track_background, exports=args.exports)
        expected = expected_files(shot, outs, review=args.review, exports=args.exports)
        if not args.force and up_to_date(shot, outs, args_, expected):
            this_run[shot.name] = UP_TO_DATE
            continue
        jobs.append(ShotJob(shot, outs, args_, runner.command(os.path.abspath(batch_script), args_), expected))
    workers = min(args.workers or default_workers(), max(1, len(jobs)))
    skipped = len(shots) - len(jobs)
    _say(f"{len(shots)} shot{'s' * (len(shots) != 1)} in {args.folder}: {len(jobs)} to build"
         + (f", {skipped} up to date (--force builds them again)" if skipped else "")
         + (f", {workers} at a time" if jobs else ""))
    by_name = {s.name: s for s in shots}
    results = []
    pool = ShotRunner(workers)
    try:
        results = pool.run(jobs, lambda r, done, total: _say(_progress_line(r, done, total, out_dir,
                                                                              by_name[r.name])))
    except KeyboardInterrupt:
        _say("interrupted: the running shots were stopped")
        return 130
    finally:
        this_run.update({r.name: BUILT for r in results if r.status == OK})
        if not args.shot:
            try:
                write_index(out_dir, shots, this_run, title=_title(args.folder))
            except InputError as exc:            # the shots are built; say why the page is missing
                print(f"batch.py: error: {exc}", file=sys.stderr)
    failed = [r for r in results if r.status == FAILED]
    _say(f"{len(results) - len(failed)} built, {len(failed)} failed, {skipped} up to date"
         + ("" if args.shot else f" -> {os.path.join(out_dir, 'index.html')}"))
    for r in failed:
        _say(f"failed: {r.name}: {r.error}")
    return 1 if failed else 0
