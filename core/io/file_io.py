"""Reading and writing files whole, with the project's rules in one place.

Why one module: every file a user hands us must fail with one line that names the
file and what is wrong (unreadable, not UTF-8, NUL bytes, empty, malformed JSON at
line/column, nested too deeply), and every file we write (tracks, truth, estimate,
CSV, plots, evaluation results) must appear whole or not at all: a crash or a full
disk never leaves a truncated file behind.  The format readers in ``core/formats``
and the project's own JSON formats share these functions instead of each keeping
a copy.
"""

from __future__ import annotations

import json
import os

from ..errors import InputError


def read_text(source: str | os.PathLike, max_bytes: int | None = None) -> str:
    """The file as text (UTF-8, BOM tolerated), or its first ``max_bytes``; empty files are an error."""
    source = os.fspath(source)
    try:
        with open(source, "rb") as fh:
            raw = fh.read() if max_bytes is None else fh.read(max_bytes)
    except OSError as exc:
        raise InputError(f"{source}: cannot read file ({exc.strerror or exc})") from None
    if max_bytes is not None and len(raw) == max_bytes:  # cut at the last full line: no split character
        raw = raw[:raw.rfind(b"\n") + 1] or raw
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{source}: not a UTF-8 text file (bad byte at offset {exc.start})") from None
    if "\x00" in text:
        raise InputError(f"{source}: contains NUL bytes; not a text file")
    if not text.strip():
        raise InputError(f"{source}: file is empty")
    return text


def read_json_file(path: str | os.PathLike):
    """Parse the JSON document at ``path``; :class:`InputError` with a one-line reason on failure.

    The non-standard ``NaN``/``Infinity`` tokens parse as numbers (Python's default), so that the
    format's own validator reports *where* a non-finite value is (frame, joint), not a bare
    parse error.
    """
    source = os.fspath(path)
    text = read_text(source)
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{source}: invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise InputError(f"{source}: JSON nested too deeply") from None


def check_output_file(path: str | os.PathLike, option: str | None = "--out") -> str:
    """``path`` as given, refused in one line unless a file can be written there: its folder exists and it
    is not a folder itself.  Called before a command's work, so that a mistyped folder fails at once
    instead of after minutes of detection, solving or training.  ``option`` names the setting the path
    came from in the message (None: the path alone)."""
    target = os.fspath(path)
    named = target if option is None else f"{option} {target}"
    folder = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(folder):
        raise InputError(f"{named}: folder {folder} does not exist")
    if os.path.isdir(target):
        raise InputError(f"{named}: is a folder, expected a file name")
    return target


def write_atomic(path: str | os.PathLike, data: str | bytes, *, what: str = "file") -> None:
    """Write ``data`` (text as UTF-8, no newline translation) through a temporary file and a rename.

    A failure to write is an :class:`InputError` naming the path (it is the user's choice of
    path that fails: a missing folder, no permission, a full disk), and the temporary file is
    removed.
    """
    target = os.fspath(path)
    tmp = f"{target}.tmp"
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        with open(tmp, "wb") as fh:
            fh.write(payload)
        os.replace(tmp, target)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(exc, OSError):
            raise InputError(f"{target}: cannot write {what} ({exc.strerror or exc})") from None
        raise


def write_json_atomic(doc, path: str | os.PathLike, *, what: str = "file", indent: int | None = None,
                      default=None) -> None:
    """``doc`` as JSON, whole or not at all (see :func:`write_atomic`).

    The document is serialised before the file is opened, so a value JSON cannot encode fails
    without touching the disk.  ``default`` converts such values (e.g. ``float`` for numpy
    scalars).
    """
    separators = None if indent is not None else (",", ":")
    write_atomic(path, json.dumps(doc, indent=indent, separators=separators, default=default), what=what)


def check_header(doc, format_name: str, version: int, where: str) -> None:
    """The ``{"format": ..., "version": ...}`` check every project file starts with."""
    if not isinstance(doc, dict) or doc.get("format") != format_name:
        raise InputError(f"{where}not a '{format_name}' file (missing \"format\": \"{format_name}\")")
    if doc.get("version") != version:
        raise InputError(f"{where}unsupported {format_name} version {doc.get('version')!r} (expected {version})")
