"""``python -m core COMMAND ...``: the no-Blender front end.

Each command lives in its own module exposing ``add_arguments(parser)`` and
``run(args) -> int``; this file only dispatches and turns
:class:`core.errors.InputError` into one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import Cancelled, InputError

#: the package these command modules are named relative to: core itself, whatever it is called inside
#: an installed extension
CORE_PACKAGE = __package__.rpartition(".")[0]

#: command -> (module relative to core, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "synth": (".cli.synth", "make synthetic 2D tracks + ground truth from a BVH or built-in motion"),
    "estimate": (".cli.estimate", "estimate proportions, camera and motion from a tracks file"),
    "evaluate": (".evaluation.evaluate", "run the paper's experiment and print accuracy tables"),
    "estimate-multiview": (".multiview.cli", "estimate from two or more synchronized views (cameras given or "
                                             "calibrated from the person)"),
    "single-image": (".single_image.cli", "pose one frame in 3D from its 2D joints (Taylor 2000)"),
    "detect": (".pose_detection.cli", "find the person's joints in a video or image frames (BlazePose, offline)"),
    "flip-depth": (".cli.flip_depth", "turn one bone of an estimate to its other side in depth over a span of frames "
                                      "(a limb mirrored in depth), the picture kept"),
    "plant-foot": (".cli.plant_foot", "hold one foot of an estimate still in the world over a span of frames (a "
                                      "planted foot that slides), the leg bent to reach it"),
    "report": (".review.cli", "write the review page of an estimate: residual and camera plots, proportions, warnings"),
    "train-prior": (".motion_prior.train", "train the pose prior from folders of BVH motion capture (training data "
                                           "only)"),
    "train-lifter": (".motion_prior.train_lifter", "train the pose lifter (one picture's joints to 3D) from folders "
                                                   "of BVH motion capture (training data only)"),
    "deepmimic-to-bvh": (".io.deepmimic", "write DeepMimic motion files (capture retargeted onto a simulated "
                                          "character) as BVH, for training"),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (none for a bare --help).

    Importing lazily keeps one broken or slow command from taking the others down.
    """
    parser = argparse.ArgumentParser(prog="python -m core", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if name == command:
            module = importlib.import_module(module_name, CORE_PACKAGE)
            module.add_arguments(p)
            p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    args = build_parser(command if command in COMMANDS else None).parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (Cancelled, KeyboardInterrupt):
        print("cancelled", file=sys.stderr)
        return 130
