"""Reading and writing the project's JSON files (tracks, truth, estimate) in one place.

Why one module: every file a user hands us must fail with one line that names the
file and what is wrong (unreadable, not UTF-8, empty, malformed at line/column,
nested too deeply), and every file we write must appear whole or not at all (a
crash or a full disk never leaves a truncated RESULT.json behind).  Writing those
rules once keeps the three formats from drifting apart.
"""

from __future__ import annotations

import json
import os

from .errors import InputError


def read_json_file(path: str | os.PathLike):
    """Parse the JSON document at ``path``; :class:`InputError` with a one-line reason on failure.

    The non-standard ``NaN``/``Infinity`` tokens parse as numbers (Python's default), so that the
    format's own validator reports *where* a non-finite value is (frame, joint), not a bare
    parse error.
    """
    source = os.fspath(path)
    try:
        with open(source, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise InputError(f"{source}: cannot read file ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise InputError(f"{source}: not a UTF-8 text file") from None
    if not text.strip():
        raise InputError(f"{source}: file is empty")
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{source}: invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise InputError(f"{source}: JSON nested too deeply") from None


def write_json_atomic(doc, path: str | os.PathLike, *, what: str = "file", indent: int | None = None) -> None:
    """Write ``doc`` to ``path`` through a temporary file and a rename: whole or not at all.

    A failure to write is an :class:`InputError` naming the path (it is the user's choice of
    path that fails: a missing folder, no permission, a full disk), and the temporary file is
    removed.
    """
    target = os.fspath(path)
    tmp = f"{target}.tmp"
    separators = None if indent is not None else (",", ":")
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=indent, separators=separators)
        os.replace(tmp, target)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(exc, OSError):
            raise InputError(f"{target}: cannot write {what} ({exc.strerror or exc})") from None
        raise


def check_header(doc, format_name: str, version: int, where: str) -> None:
    """The ``{"format": ..., "version": ...}`` check every project file starts with."""
    if not isinstance(doc, dict) or doc.get("format") != format_name:
        raise InputError(f"{where}not a '{format_name}' file (missing \"format\": \"{format_name}\")")
    if doc.get("version") != version:
        raise InputError(f"{where}unsupported {format_name} version {doc.get('version')!r} (expected {version})")
