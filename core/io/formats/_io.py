"""Low-level reading shared by the format readers: CSV rows and numbers (whole-file text and JSON
reading is :mod:`core.io.file_io`, shared with the project's own formats).

Every helper turns OS, decoding and parsing failures into :class:`InputError`
with the file name, so that a reader never lets a bare ``OSError``,
``UnicodeDecodeError`` or ``json.JSONDecodeError`` escape to the user.
"""

from __future__ import annotations

import csv
import io
import math
import re

import numpy as np

from ...errors import InputError
from ..file_io import read_text

#: Gap-filled frame numbers may span at most this many frames beyond ten per row
#: given; a wider span means the numbers are not frame numbers (or a typo).
MAX_EXTRA_SPAN = 100_000


def csv_rows(source: str, limit: int | None = None) -> list[tuple[int, list[str]]]:
    """Non-blank CSV rows of ``source`` as (1-based line number, stripped cells); at most ``limit`` rows.

    Lines starting with ``#`` are kept (the generic CSV reads settings from them);
    callers that do not want them filter on ``cells[0].startswith("#")``.
    """
    text = read_text(source, None if limit is None else 1 << 16)
    rows = []
    reader = csv.reader(io.StringIO(text, newline=""))
    # strip cells only when some may need it: large clean files read several times faster
    padded = any((" " in line or "\t" in line) and not line.startswith("#") for line in text.splitlines())
    try:
        for cells in reader:
            if padded:
                cells = [c.strip() for c in cells]
            if len(cells) > 1 or (cells and cells[0]):
                rows.append((reader.line_num, cells))
                if limit is not None and len(rows) >= limit:
                    break
    except csv.Error as exc:
        raise InputError(f"{source}: line {reader.line_num}: malformed CSV ({exc})") from None
    if not rows:
        raise InputError(f"{source}: file is empty")
    return rows


def check_row_widths(rows: list[tuple[int, list[str]]], width: int, source: str) -> None:
    """Every (line, cells) row has ``width`` cells, else an InputError naming the first bad line."""
    for line, cells in rows:
        if len(cells) != width:
            raise InputError(f"{source}: line {line}: {len(cells)} cells but the header has {width}")


def finite_float(value) -> float | None:
    """``value`` as a finite float if it is a JSON/CSV number, else None (bools are not numbers)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, str):
        text = value.strip()
        if not text:
            return None
        try:
            out = float(text)
        except ValueError:
            return None
    elif isinstance(value, (int, float)):
        try:
            out = float(value)
        except OverflowError:
            return None
    else:
        return None
    return out if math.isfinite(out) else None


def parse_int(text: str) -> int | None:
    """A frame number written as an integer (``"12"``, also ``"12.0"``), else None."""
    text = text.strip()
    if re.fullmatch(r"[+-]?\d{1,15}", text):
        return int(text)
    value = finite_float(text)
    if value is not None and value.is_integer() and abs(value) < 1e15:
        return int(value)
    return None


def natural_key(name: str) -> tuple:
    """Sort key that orders ``frame_2`` before ``frame_10`` (digit runs compared as numbers).

    Numbers are compared by length, then digits, after dropping leading
    zeros: the numeric order without converting (arbitrarily long) digit runs to int.
    """
    parts = re.split(r"(\d+)", name)
    key = []
    for p in parts:
        if p.isdigit():
            digits = p.lstrip("0")
            key.append((0, len(digits), digits))
        elif p:
            key.append((1, 0, p))
    return tuple(key)


def frame_positions(numbers, source: str, what: str = "frame numbers") -> tuple[np.ndarray, int, int]:
    """Map frame numbers to track rows, filling gaps as missing frames.

    Returns (row index per number, first frame number, track length).  Files
    that skip frames without a detection keep their timing this way; a span
    far wider than the data (e.g. a typo like 1000000) is refused instead of
    silently allocating a huge, empty clip.
    """
    try:
        numbers = np.asarray(numbers, dtype=np.int64)
    except OverflowError:
        raise InputError(f"{source}: {what} too large to be frame numbers") from None
    if numbers.size == 0:
        raise InputError(f"{source}: no frames")
    first, last = int(numbers.min()), int(numbers.max())
    if first < 0:
        raise InputError(f"{source}: negative frame number {first}")
    distinct = len(np.unique(numbers))
    span = last - first + 1
    if span > 10 * distinct + MAX_EXTRA_SPAN:
        raise InputError(f"{source}: {what} run from {first} to {last} but only {distinct} are present; "
                         "they do not look like frame numbers")
    return numbers - first, first, span


def float_column(values: list[str], lines: list[int], source: str, what: str, *,
                 allow_empty: bool = False) -> np.ndarray:
    """Cells of one CSV column as finite floats; the first bad cell is reported with its line.

    numpy parses the whole column at once (the common, clean case); only when
    that fails is the column walked cell by cell to name the offending line.
    With ``allow_empty`` an empty cell becomes NaN (a missing value), while a
    literal ``nan`` is still refused.
    """
    try:
        cells = [v or "nan" for v in values] if allow_empty else values
        arr = np.array(cells, dtype=float)
        finite = np.isfinite(arr)
        if allow_empty:
            finite |= np.array([not v for v in values], dtype=bool)
        if arr.shape == (len(values),) and finite.all():
            return arr
    except (ValueError, TypeError, OverflowError):
        pass
    out = np.empty(len(values))
    for k, text in enumerate(values):
        v = np.nan if allow_empty and not text else finite_float(text)
        if v is None:
            raise InputError(f"{source}: line {lines[k]}: {what} {text!r} is not a finite number")
        out[k] = v
    return out


def int_column(values: list[str], lines: list[int], source: str, what: str) -> np.ndarray:
    """Cells of one CSV column as integers (``12`` or ``12.0``), reporting the first bad line."""
    try:
        arr = np.array(values, dtype=np.int64)
        if arr.shape == (len(values),) and (np.abs(arr) < 10**15).all():
            return arr
    except (ValueError, TypeError, OverflowError):
        pass
    out = np.empty(len(values), dtype=np.int64)
    for k, text in enumerate(values):
        v = parse_int(text)
        if v is None:
            raise InputError(f"{source}: line {lines[k]}: {what} {text!r} is not an integer")
        out[k] = v
    return out
