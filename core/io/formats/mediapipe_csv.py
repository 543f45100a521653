"""MediaPipe Pose landmarks in a CSV file, in one of two shapes (detected from the header).

* **long**: one row per landmark, columns ``frame, landmark, x, y`` and
  optionally ``z``, ``visibility``, ``presence``; ``landmark`` is the index
  0..32 or the MediaPipe name (``left_shoulder``).  A frame lists all 33
  landmarks or is absent (no detection).
* **wide**: one row per frame, columns ``<landmark>_x``, ``<landmark>_y``
  (and ``_z``, ``_visibility``) for all 33 landmarks, where ``<landmark>`` is
  the name or the index (``11_x``; ``x11`` / ``x_11`` also work), and an
  optional ``frame`` column.  A row whose landmark cells are all empty is a
  frame without detection.

Frame numbers (when present) order the rows; gaps become empty frames.
Other columns (timestamps, file names) are ignored.  The CSV has no frame
rate or image size: both come from the arguments.
"""

from __future__ import annotations

import re

import numpy as np

from ...errors import InputError
from ...tracks import Tracks
from ._canonical import choose_fps, choose_image_size
from ._io import check_row_widths, csv_rows, finite_float, float_column, frame_positions, int_column, parse_int
from .mediapipe import N_LANDMARKS, landmark_index, landmarks_to_tracks

LABEL = "MediaPipe CSV"
COORDS = {"x": 0, "y": 1, "visibility": 2, "v": 2, "vis": 2}
_IGNORED_COORDS = {"z", "presence"}


def wide_column(name: str) -> tuple[int, str] | None:
    """(landmark index, coordinate) for a wide-format column name, else None."""
    name = name.strip().lower()
    m = re.fullmatch(r"(?:landmark_?)?(.+?)[_.](x|y|z|visibility|vis|v|presence)", name)
    if m:
        i = landmark_index(m.group(1))
        if i is not None:
            return i, m.group(2)
    m = re.fullmatch(r"(x|y|z|visibility|vis|v|presence)_?(\d+)", name)
    if m:
        i = landmark_index(m.group(2))
        if i is not None:
            return i, m.group(1)
    return None


def is_mediapipe_header(cells: list[str]) -> bool:
    """True when a header row looks like either MediaPipe CSV shape (for auto-detection)."""
    lowered = {c.lower() for c in cells}
    if {"frame", "landmark", "x", "y"} <= lowered:
        return True
    return sum(wide_column(c) is not None for c in cells) >= 2 * N_LANDMARKS


def _number(text: str, source: str, line: int, what: str) -> float:
    value = finite_float(text)
    if value is None:
        raise InputError(f"{source}: line {line}: {what} {text!r} is not a finite number")
    return value


def _read_long(rows, header, source):
    col = {c.lower(): k for k, c in enumerate(header)}
    lines = [line for line, _ in rows]
    check_row_widths(rows, len(header), source)
    column = {name: [cells[k] for _, cells in rows] for name, k in col.items()}
    frames = int_column(column["frame"], lines, source, "frame")
    known: dict[str, int | None] = {}
    marks = np.empty(len(rows), dtype=np.int64)
    for k, key in enumerate(column["landmark"]):
        if key not in known:
            known[key] = landmark_index(key)
        if known[key] is None:
            raise InputError(f"{source}: line {lines[k]}: unknown landmark {key!r} "
                             "(use 0..32 or a MediaPipe Pose name such as left_shoulder)")
        marks[k] = known[key]
    x = float_column(column["x"], lines, source, "x")
    y = float_column(column["y"], lines, source, "y")
    vis = (float_column(column["visibility"], lines, source, "visibility") if "visibility" in col
           else np.ones(len(rows)))
    if (vis < 0).any():
        raise InputError(f"{source}: line {lines[int(np.argmax(vis < 0))]}: negative visibility")
    rows_of, first, n = frame_positions(frames, source)
    key = rows_of * N_LANDMARKS + marks
    _, first_seen, counts = np.unique(key, return_index=True, return_counts=True)
    if (counts > 1).any():
        dup = np.flatnonzero(key == key[first_seen[np.argmax(counts > 1)]])[1]
        raise InputError(f"{source}: line {lines[dup]}: landmark {marks[dup]} listed twice in frame {frames[dup]}")
    per_frame = np.bincount(rows_of, minlength=n)
    ragged = np.flatnonzero((per_frame > 0) & (per_frame != N_LANDMARKS))
    if ragged.size:
        r = ragged[0]
        last_line = max(line for line, row in zip(lines, rows_of, strict=True) if row == r)
        raise InputError(f"{source}: frame {r + first} (ending line {last_line}) has {per_frame[r]} landmarks; "
                         f"MediaPipe Pose frames have all {N_LANDMARKS}")
    xy = np.full((n, N_LANDMARKS, 2), np.nan)
    out_vis = np.zeros((n, N_LANDMARKS))
    xy[rows_of, marks] = np.column_stack([x, y])
    out_vis[rows_of, marks] = vis
    return xy, out_vis, first


def _read_wide(rows, header, source):
    columns: dict[tuple[int, str], int] = {}
    frame_col = None
    for k, name in enumerate(header):
        parsed = wide_column(name)
        if parsed is not None:
            columns[parsed] = k
        elif name.lower() == "frame":
            frame_col = k
    lacking = [f"{i}_{c}" for i in range(N_LANDMARKS) for c in ("x", "y") if (i, c) not in columns]
    if lacking:
        raise InputError(f"{source}: line 1: missing columns {lacking[:6]}{' ...' if len(lacking) > 6 else ''}; "
                         f"need x and y for all {N_LANDMARKS} landmarks")
    vis_cols = {i: k for (i, c), k in columns.items() if COORDS.get(c) == 2}
    used_cols = [k for (i, c), k in columns.items() if c not in _IGNORED_COORDS]
    numbers, data = [], []
    for r, (line, cells) in enumerate(rows):
        if len(cells) != len(header):
            raise InputError(f"{source}: line {line}: {len(cells)} cells but the header has {len(header)}")
        if frame_col is None:
            numbers.append(r)
        else:
            frame = parse_int(cells[frame_col])
            if frame is None:
                raise InputError(f"{source}: line {line}: frame {cells[frame_col]!r} is not an integer")
            numbers.append(frame)
        filled = [bool(cells[k]) for k in used_cols]
        if not any(filled):
            data.append(None)
            continue
        if not all(filled):
            raise InputError(f"{source}: line {line}: some landmark cells are empty; a row holds all "
                             f"{N_LANDMARKS} landmarks or none")
        pts = np.array([[_number(cells[columns[(i, c)]], source, line, f"{i}_{c}") for c in ("x", "y")]
                        for i in range(N_LANDMARKS)])
        vis = np.ones(N_LANDMARKS)
        for i, k in vis_cols.items():
            vis[i] = _number(cells[k], source, line, f"{i}_visibility")
            if vis[i] < 0:
                raise InputError(f"{source}: line {line}: negative visibility for landmark {i}")
        data.append((pts, vis, line))
    if len(set(numbers)) != len(numbers):
        raise InputError(f"{source}: frame number listed twice")
    rows_of, first, n = frame_positions(numbers, source)
    xy = np.full((n, N_LANDMARKS, 2), np.nan)
    vis_all = np.zeros((n, N_LANDMARKS))
    for r, item in zip(rows_of, data, strict=True):
        if item is not None:
            xy[r], vis_all[r] = item[0], item[1]
    return xy, vis_all, first


def read_mediapipe_csv(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    rows = [r for r in csv_rows(source) if not r[1][0].startswith("#")]
    if not rows:
        raise InputError(f"{source}: file is empty")
    header = rows[0][1]
    lowered = [c.lower() for c in header]
    if len(set(lowered)) != len(lowered):
        raise InputError(f"{source}: line {rows[0][0]}: a column name is repeated in the header")
    if len(rows) < 2:
        raise InputError(f"{source}: header only; no frames")
    if "landmark" in lowered:
        missing = [c for c in ("frame", "landmark", "x", "y") if c not in lowered]
        if missing:
            raise InputError(f"{source}: line {rows[0][0]}: missing columns {missing}")
        shape = "long"
        xy, vis, first = _read_long(rows[1:], header, source)
    else:
        shape = "wide"
        xy, vis, first = _read_wide(rows[1:], header, source)
    fps = choose_fps(fps, None, LABEL, source)
    image_size = choose_image_size(image_size, None, LABEL, source)
    meta = {"format": "mediapipe_csv", "csv_shape": shape, "first_frame": first}
    return landmarks_to_tracks(xy, vis, fps=fps, image_size=image_size, source=source, meta=meta)
