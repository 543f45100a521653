"""The single-shot batch command each worker runs, and the options every shot of a folder shares.

A worker is the same program that runs the folder: the Python with the ``bpy`` module
(``python batch.py -- ...``) or Blender itself (``blender -b --python batch.py -- ...``), so a folder built
in Blender is built by that Blender.  The shared options are the ones the user gave to the folder run,
written back out as the user gave them (argparse resolves abbreviations; values are kept as typed), less
the folder's own options; each shot then adds its input and its outputs.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass

from .discover import VIDEO, Shot
from .outputs import ShotOutputs

PYTHON, BLENDER = "python", "blender"
#: Blender's flags before ``--python``: no window, no user preferences or add-ons, a failing script fails.
BLENDER_FLAGS = ("-b", "--factory-startup", "--python-exit-code", "1", "--python")


@dataclass(frozen=True)
class Runner:
    """How to start the single-shot batch: ``kind`` PYTHON (a Python with bpy) or BLENDER, and its program."""

    kind: str
    executable: str

    def command(self, batch_script: str, args: list[str]) -> list[str]:
        """The whole command line running ``batch_script`` with ``args``."""
        flags = list(BLENDER_FLAGS) if self.kind == BLENDER else []
        return [self.executable, *flags, batch_script, "--", *args]


def current_runner(blender_module=None) -> Runner:
    """The runner of this process: real Blender when ``blender_module`` (bpy, imported by Blender before the
    script ran) names a Blender binary, else this Python (which imports the bpy module itself)."""
    import sys

    binary = getattr(getattr(blender_module, "app", None), "binary_path", "") if blender_module else ""
    if binary:
        return Runner(BLENDER, binary)
    return Runner(PYTHON, sys.executable)


def given_options(parser: argparse.ArgumentParser, argv: list[str]) -> dict[str, tuple[str, list[str] | None]]:
    """dest -> (option string, raw values or None for a flag) for each option present in ``argv``.

    ``argv`` is parsed again by a copy of ``parser`` whose options keep their text (no type conversion,
    no defaults), so what comes back is exactly what the user typed, abbreviations resolved.
    ``argv`` must already be valid for ``parser``.
    """
    raw = argparse.ArgumentParser(add_help=False, prefix_chars=parser.prefix_chars)
    spelled = {}
    for action in parser._actions:       # argparse offers no public way to list a parser's arguments
        if isinstance(action, argparse._HelpAction):
            continue
        if not action.option_strings:
            raw.add_argument(action.dest, nargs="?" if action.nargs is None else action.nargs,
                             default=argparse.SUPPRESS)
            spelled[action.dest] = None
            continue
        long = next((s for s in action.option_strings if s.startswith("--")), action.option_strings[0])
        spelled[action.dest] = long
        if action.nargs == 0:
            raw.add_argument(*action.option_strings, dest=action.dest, action="store_const", const=None,
                             default=argparse.SUPPRESS)
        else:
            raw.add_argument(*action.option_strings, dest=action.dest, nargs=action.nargs,
                             default=argparse.SUPPRESS)
    found = vars(raw.parse_args(argv))
    given = {}
    for dest, value in found.items():
        if value is None:
            given[dest] = (spelled[dest], None)
        else:
            given[dest] = (spelled[dest], list(value) if isinstance(value, list) else [value])
    return given


def option_arguments(given: dict[str, tuple[str, list[str] | None]], keep) -> list[str]:
    """``given`` (see :func:`given_options`) back as arguments, only the dests in ``keep``, in its order.

    One value is written ``--option=value``, so a value that starts with '-' stays a value."""
    args: list[str] = []
    for dest, (option, values) in given.items():
        if dest not in keep or option is None:
            continue
        if values is None:
            args.append(option)
        elif len(values) == 1:
            args.append(f"{option}={values[0]}")
        else:
            args += [option, *values]
    return args


def shot_arguments(shot: Shot, outs: ShotOutputs, shared: list[str], *, track_background: bool = False,
                   exports=()) -> list[str]:
    """The single-shot batch's arguments for ``shot``: its input, the shared options, its outputs."""
    args = ["--video", shot.path] if shot.kind == VIDEO else [shot.path]
    args += shared
    args += ["--output", outs.blend, "--result", outs.result]
    if shot.kind == VIDEO:
        args += ["--tracks-out", outs.tracks]
    elif track_background and shot.footage:
        args += ["--footage", shot.footage]
    for ext in exports:
        args += [f"--{ext}", outs.export(ext)]
    return args


def absolute_rig_spec(spec: str) -> str:
    """``--target-rig FILE.blend:ARMATURE`` with FILE made absolute, so it holds from any working folder."""
    path, sep, name = spec.rpartition(":")
    return f"{os.path.abspath(path)}{sep}{name}" if sep and path else spec
