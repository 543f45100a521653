"""The generic long CSV ``frame,joint,x,y[,confidence]`` with canonical joint names, and its writer.

One row per observed joint: ``frame`` an integer, ``joint`` one of the 17
canonical names, ``x``/``y`` pixels (origin top-left, y down), optional
``confidence`` in 0..1 (1 when the column is absent; 0 = missing).  Joints
without a row are missing; frames are numbered from the smallest frame in the
file, gaps become empty frames.  Columns may come in any order; any other
column is an error (so a misspelt ``confidence`` is not silently ignored).

Optional comment lines before the header carry the clip settings, as the
writer produces them::

    # fps: 30
    # image_size: 720 480
    # frames: 120

``# frames: N`` says the clip has frames 0..N-1 (so empty frames at either
end survive a round trip); without it, frames run from the smallest to the
largest frame number in the file.

Rows whose ``joint`` is not a canonical name are static scene points (a floor
mark, a wall corner: :class:`core.tracks.StaticTracks`), kept under their own
names; a name within a typo of a joint name is an error instead, so a misspelt
joint is not taken for scenery.  ``# ignore: name name ...`` leaves static
points out.

Nothing is derived: the file already speaks the canonical joints.
"""

from __future__ import annotations

import difflib
import os

import numpy as np

from ...errors import InputError
from ...skeleton import JOINT_INDEX, JOINTS, N_JOINTS
from ...tracks import StaticTracks, Tracks
from ..file_io import write_atomic
from ._canonical import check_fps, check_image_size, choose_fps, choose_image_size
from ._io import (
    MAX_EXTRA_SPAN,
    check_row_widths,
    csv_rows,
    finite_float,
    float_column,
    frame_positions,
    int_column,
    parse_int,
)

LABEL = "generic CSV"
REQUIRED = ("frame", "joint", "x", "y")
OPTIONAL = ("confidence",)


def _settings(comments: list[tuple[int, list[str]]], source: str):
    """(fps, image size, frame count) from ``# key: value`` comment lines; None for each one absent."""
    fps = size = count = None
    ignore: set[str] = set()
    for line, cells in comments:
        text = ",".join(cells).lstrip("#").strip()
        key, sep, value = text.partition(":")
        key = key.strip().lower()
        if sep and key == "ignore":
            ignore.update(value.replace(",", " ").split())
            continue
        if not sep or key not in ("fps", "image_size", "frames"):
            continue
        if key == "frames":
            count = parse_int(value)
            if count is None or count <= 0:
                raise InputError(f"{source}: line {line}: '# frames:' needs a positive integer, got {value.strip()!r}")
            continue
        parts = value.replace(",", " ").replace("x", " ").split()
        if key == "fps":
            if len(parts) != 1 or finite_float(parts[0]) is None or finite_float(parts[0]) <= 0:
                raise InputError(f"{source}: line {line}: '# fps:' needs one positive number, got {value.strip()!r}")
            fps = check_fps(finite_float(parts[0]), source)
        else:
            nums = [finite_float(p) for p in parts]
            if len(nums) != 2 or any(v is None or v <= 0 for v in nums):
                raise InputError(f"{source}: line {line}: '# image_size:' needs width and height, "
                                 f"got {value.strip()!r}")
            size = check_image_size(nums, source)
    return fps, size, count, ignore


def read_generic_csv(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    rows = csv_rows(source)
    comments = [r for r in rows if r[1][0].startswith("#")]
    rows = [r for r in rows if not r[1][0].startswith("#")]
    file_fps, file_size, count, ignore = _settings(comments, source)
    if not rows:
        raise InputError(f"{source}: no header line (expected {','.join(REQUIRED)}[,confidence])")
    head_line, header = rows[0]
    header = [c.lower() for c in header]
    unknown = [c for c in header if c not in REQUIRED + OPTIONAL]
    missing = [c for c in REQUIRED if c not in header]
    if missing or unknown:
        what = "; ".join(p for p in (f"missing columns {missing}" if missing else "",
                                     f"unknown columns {unknown}" if unknown else "") if p)
        raise InputError(f"{source}: line {head_line}: {what}; the header must be frame,joint,x,y[,confidence]")
    if len(set(header)) != len(header):
        raise InputError(f"{source}: line {head_line}: a column is named twice")
    col = {c: k for k, c in enumerate(header)}
    if len(rows) < 2:
        raise InputError(f"{source}: header only; no frames")
    body = rows[1:]
    lines = [line for line, _ in body]
    check_row_widths(body, len(header), source)
    columns = {name: [cells[k] for _, cells in body] for name, k in col.items()}
    frames = int_column(columns["frame"], lines, source, "frame")
    statics: list[str] = []
    joints = np.empty(len(body), dtype=np.int64)
    for k, name in enumerate(columns["joint"]):
        j = JOINT_INDEX.get(name)
        if j is None:
            close = difflib.get_close_matches(name, JOINTS, n=1, cutoff=0.8)
            if close or not name:
                raise InputError(f"{source}: line {lines[k]}: unknown joint {name!r}"
                                 + (f" (did you mean {close[0]!r}?)" if close else "")
                                 + f"; expected one of {list(JOINTS)}, or a static point's own name")
            if name not in statics:
                statics.append(name)
            j = N_JOINTS + statics.index(name)
        joints[k] = j
    x = float_column(columns["x"], lines, source, "x")
    y = float_column(columns["y"], lines, source, "y")
    c = float_column(columns["confidence"], lines, source, "confidence") if "confidence" in col else np.ones(len(x))
    if (c < 0).any():
        k = int(np.argmax(c < 0))
        raise InputError(f"{source}: line {lines[k]}: negative confidence {c[k]}")
    n_points = N_JOINTS + len(statics)
    if count is None:
        rows_of, first, n = frame_positions(frames, source)
    else:
        if count > 10 * len(np.unique(frames)) + MAX_EXTRA_SPAN:
            raise InputError(f"{source}: '# frames: {count}' is far more than the {len(np.unique(frames))} "
                             "frames listed")
        bad = np.flatnonzero((frames < 0) | (frames >= count))
        if bad.size:
            raise InputError(f"{source}: line {lines[bad[0]]}: frame {frames[bad[0]]} is outside 0..{count - 1} "
                             f"set by '# frames: {count}'")
        rows_of, first, n = frames, 0, count
    key = rows_of * n_points + joints
    _, first_seen, counts = np.unique(key, return_index=True, return_counts=True)
    if (counts > 1).any():
        dup = np.flatnonzero(key == key[first_seen[np.argmax(counts > 1)]])[1]
        kind = "joint" if joints[dup] < N_JOINTS else "static point"
        raise InputError(f"{source}: line {lines[dup]}: {kind} {columns['joint'][dup]!r} listed twice in frame "
                         f"{frames[dup]}")
    xy = np.full((n, n_points, 2), np.nan)
    conf = np.zeros((n, n_points))
    xy[rows_of, joints] = np.column_stack([x, y])
    conf[rows_of, joints] = np.minimum(c, 1.0)
    if not (conf[:, :N_JOINTS] > 0).any():
        raise InputError(f"{source}: no joint is present (every joint has confidence 0 or no row)")
    fps = choose_fps(fps, file_fps, LABEL, source)
    image_size = choose_image_size(image_size, file_size, LABEL, source)
    static = None
    if statics:
        static = StaticTracks(statics, xy[:, N_JOINTS:], conf[:, N_JOINTS:]).without(ignore)
    return Tracks(xy[:, :N_JOINTS], conf[:, :N_JOINTS], fps, image_size, source,
                  {"format": "generic_csv", "first_frame": first}, static)


def write_generic_csv(tracks: Tracks, path: str | os.PathLike, *, decimals: int = 4) -> None:
    """Write ``tracks`` as a generic CSV (present joints only, settings in comment lines), atomically.

    Values are rounded to ``decimals`` places; a confidence that would round
    to 0 is written as the smallest step so the joint stays present.
    """
    lines = [f"# fps: {tracks.fps!r}",
             f"# image_size: {tracks.image_size[0]!r} {tracks.image_size[1]!r}",
             f"# frames: {tracks.n_frames}",
             "frame,joint,x,y,confidence"]
    groups = [(JOINTS, tracks.xy, tracks.conf)]
    if tracks.static is not None:
        groups.append((tracks.static.names, tracks.static.xy, tracks.static.conf))
    for f in range(tracks.n_frames):
        for names, xy, conf in groups:
            for k, name in enumerate(names):
                c = float(conf[f, k])
                if c > 0:
                    x, y = (round(float(v), decimals) for v in xy[f, k])
                    c = max(round(c, decimals), 10.0 ** -decimals)
                    lines.append(f"{f},{name},{x!r},{y!r},{c!r}")
    write_atomic(path, "\n".join(lines) + "\n", what="CSV file")
