"""BVH reader and vectorised forward kinematics.

Why our own reader: the core must not import ``bpy`` and must be fast on
long clips (the synthetic experiment reads thousands of frames), and every
user mistake must become a one-line :class:`InputError` naming the file and
line.

Conventions (the same as Blender's ``io_anim_bvh`` importer, which the
Blender test checks us against):

* Every ``End Site`` becomes a node of its own (``is_end_site``, no
  channels, named ``"<parent>_End"``), so head tops and toe tips have world
  positions like any joint.  Nodes are in file order, parents first.
* A joint's local rotation is the product of its rotation channels in the
  order they are listed: ``Zrotation Xrotation Yrotation`` means
  ``R = Rz @ Rx @ Ry`` (column vectors, degrees in the file).
* A joint with any position channel takes its translation from them
  (missing components are 0) *instead of* its ``OFFSET``; otherwise the
  ``OFFSET`` is the translation.  The root's translation is in world axes;
  a child's is in its parent's rotated frame.
* Units and axes are left exactly as in the file; :func:`up_axis` detects
  whether the figure stands along Y or Z.
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError

_ROT_AXES = {"xrotation": 0, "yrotation": 1, "zrotation": 2}
_POS_AXES = {"xposition": 0, "yposition": 1, "zposition": 2}
_PLANE = ((1, 2), (2, 0), (0, 1))  # the two axes an x/y/z rotation mixes
_MOTION = re.compile(r"^[ \t]*MOTION[ \t]*\r?$", re.MULTILINE | re.IGNORECASE)


@dataclass
class Bvh:
    """A parsed BVH file.

    ``motion`` is (F, C) with the channel values as in the file (degrees,
    file units); ``channels[j]`` lists joint ``j``'s channel names
    (lower-case) and ``channel_start[j]`` its first column in ``motion``.
    """

    path: str
    names: list[str]
    parents: np.ndarray            # (J,) int, -1 for the root
    offsets: np.ndarray            # (J, 3) file units
    is_end_site: np.ndarray        # (J,) bool
    channels: list[tuple[str, ...]]
    channel_start: np.ndarray      # (J,) int
    frame_time: float
    motion: np.ndarray             # (F, C)
    children: list[list[int]] = field(default_factory=list)

    def __post_init__(self):
        if not self.children:
            self.children = [[] for _ in self.names]
            for j, p in enumerate(self.parents):
                if p >= 0:
                    self.children[p].append(j)

    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    def index(self, name: str) -> int:
        """Index of the node called ``name`` (KeyError if absent)."""
        return self.names.index(name)

    def world_positions(self, frames=None) -> np.ndarray:
        """World positions (F, J, 3) of every node, End Sites included, in file units/axes."""
        return self._forward_kinematics(frames, want_rotations=False)[0]

    def world_transforms(self, frames=None) -> tuple[np.ndarray, np.ndarray]:
        """World positions (F, J, 3) and world rotations (F, J, 3, 3) of every node.

        ``frames`` is None (all), a slice, or an index array.
        """
        return self._forward_kinematics(frames, want_rotations=True)

    def rest_positions(self) -> np.ndarray:
        """World positions (J, 3) with every channel zero and offsets as translations."""
        out = np.zeros((self.n_joints, 3))
        for j, p in enumerate(self.parents):
            out[j] = self.offsets[j] if p < 0 else out[p] + self.offsets[j]
        return out

    def _forward_kinematics(self, frames, want_rotations: bool):
        """All frames at once; the only Python loop is over joints and their channels.

        A world rotation is kept as its three columns, each (F, 3) and
        contiguous: multiplying by an axis rotation on the right mixes just two
        columns (``R @ Rx(t)``: col_y' = c col_y + s col_z, col_z' = c col_z - s col_y),
        so no 3x3 products are formed, and a translation is
        ``sum_k col_k * t_k``.
        """
        data = self.motion if frames is None else self.motion[frames]
        data = np.atleast_2d(data)
        n = data.shape[0]
        columns = np.ascontiguousarray(data.T)                         # (C, F)
        radians = np.radians(columns)
        cos, sin = np.cos(radians), np.sin(radians)
        positions: list[np.ndarray] = []
        frames_cols: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        unit = np.eye(3)
        for j in range(self.n_joints):
            p = int(self.parents[j])
            start = int(self.channel_start[j])
            translation = None
            for k, name in enumerate(self.channels[j]):
                if name in _POS_AXES:
                    if translation is None:
                        translation = [0.0, 0.0, 0.0]
                    translation[_POS_AXES[name]] = columns[start + k]
            if translation is None:
                translation = [float(v) for v in self.offsets[j]]
            if p < 0:
                cols = [np.broadcast_to(unit[:, k], (n, 3)) for k in range(3)]
                pos = np.empty((n, 3))
                for a in range(3):
                    pos[:, a] = translation[a]
            else:
                cols = list(frames_cols[p])
                pos = positions[p].copy()
                for a in range(3):
                    t = translation[a]
                    if isinstance(t, np.ndarray):
                        pos += cols[a] * t[:, None]
                    elif t != 0.0:
                        pos += cols[a] * t
            for k, name in enumerate(self.channels[j]):
                axis = _ROT_AXES.get(name)
                if axis is None:
                    continue
                a, b = _PLANE[axis]
                c, s = cos[start + k][:, None], sin[start + k][:, None]
                cols[a], cols[b] = cols[a] * c + cols[b] * s, cols[b] * c - cols[a] * s
            positions.append(pos)
            frames_cols.append((cols[0], cols[1], cols[2]))
        world = np.stack(positions, axis=1)
        if not want_rotations:
            return world, None
        rotations = np.empty((n, self.n_joints, 3, 3))
        for j, cols in enumerate(frames_cols):
            for k in range(3):
                rotations[:, j, :, k] = cols[k]
        return world, rotations


def axis_rotations(axis: int, angles: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) about coordinate ``axis`` (0=x, 1=y, 2=z) by ``angles`` radians."""
    c, s = np.cos(angles), np.sin(angles)
    out = np.zeros(angles.shape + (3, 3))
    a, b = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., a, a] = c
    out[..., b, b] = c
    out[..., a, b] = -s
    out[..., b, a] = s
    return out


# --------------------------------------------------------------------------- reading


class _Tokens:
    """Whitespace tokens of the HIERARCHY part with their 1-based line numbers."""

    def __init__(self, path: str, lines: list[str]):
        self.path = path
        self.items: list[tuple[str, int]] = []
        for number, line in enumerate(lines, start=1):
            for token in line.split():
                self.items.append((token, number))
        self.pos = 0

    def error(self, message: str, line: int | None = None) -> InputError:
        if line is None:
            line = self.items[min(self.pos, len(self.items) - 1)][1] if self.items else 1
        return InputError(f"{self.path}, line {line}: {message}")

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def next(self, what: str) -> tuple[str, int]:
        if self.pos >= len(self.items):
            last = self.items[-1][1] if self.items else 1
            raise self.error(f"unexpected end of file, expected {what}", last)
        item = self.items[self.pos]
        self.pos += 1
        return item

    def expect(self, word: str) -> int:
        token, line = self.next(repr(word))
        if token.lower() != word.lower():
            raise self.error(f"expected {word!r}, found {token!r}", line)
        return line

    def number(self, what: str) -> float:
        token, line = self.next(what)
        try:
            value = float(token)
        except ValueError:
            raise self.error(f"expected a number for {what}, found {token!r}", line) from None
        if not np.isfinite(value):
            raise self.error(f"{what} is not finite ({token!r})", line)
        return value

    def rest_of_line(self, line: int) -> list[str]:
        out = []
        while self.pos < len(self.items) and self.items[self.pos][1] == line:
            out.append(self.items[self.pos][0])
            self.pos += 1
        return out


def read_bvh(path) -> Bvh:
    """Parse a BVH file (any channel order, End Sites, tabs, CRLF, blank lines)."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8-sig", errors="replace", newline=None) as handle:
            text = handle.read()
    except OSError as exc:
        raise InputError(f"cannot read BVH file {path}: {exc.strerror or exc}") from None
    return parse_bvh(text, path)


def parse_bvh(text: str, path: str = "<bvh>") -> Bvh:
    """Parse BVH ``text``; ``path`` only names the source in error messages."""
    if not text.strip():
        raise InputError(f"{path}: empty file")
    found = _MOTION.search(text)
    if found is None:
        raise InputError(f"{path}: no MOTION section (not a BVH file?)")
    lines = text[:found.start()].splitlines()
    motion_line = text.count("\n", 0, found.start())      # 0-based line number of "MOTION"
    tokens = _Tokens(path, lines[:motion_line])
    first, line = tokens.next("HIERARCHY")
    if first.upper() != "HIERARCHY":
        raise tokens.error(f"expected 'HIERARCHY', found {first!r} (not a BVH file?)", line)

    names: list[str] = []
    parents: list[int] = []
    offsets: list[tuple[float, float, float]] = []
    end_site: list[bool] = []
    channels: list[tuple[str, ...]] = []
    channel_start: list[int] = []
    n_channels = 0

    def parse_node(parent: int, kind_line: int, is_end: bool, name: str) -> None:
        nonlocal n_channels
        index = len(names)
        names.append(name)
        parents.append(parent)
        end_site.append(is_end)
        tokens.expect("{")
        tokens.expect("OFFSET")
        offsets.append(tuple(tokens.number(f"the OFFSET of {name!r}") for _ in range(3)))
        channel_start.append(n_channels)
        joint_channels: tuple[str, ...] = ()
        if not is_end and (tokens.peek() or "").upper() == "CHANNELS":
            tokens.next("CHANNELS")
            count_token, count_line = tokens.next("the channel count")
            try:
                count = int(count_token)
            except ValueError:
                raise tokens.error(f"channel count of {name!r} is not an integer: {count_token!r}",
                                   count_line) from None
            if count < 0 or count > 6:
                raise tokens.error(f"{name!r} has {count} channels (0..6 allowed)", count_line)
            found = []
            for _ in range(count):
                channel, channel_line = tokens.next(f"a channel name of {name!r}")
                low = channel.lower()
                if low not in _ROT_AXES and low not in _POS_AXES:
                    raise tokens.error(f"unknown channel {channel!r} on {name!r}", channel_line)
                if low in found:
                    raise tokens.error(f"channel {channel!r} repeated on {name!r}", channel_line)
                found.append(low)
            joint_channels = tuple(found)
        channels.append(joint_channels)
        n_channels += len(joint_channels)
        while True:
            token, token_line = tokens.next(f"'}}' closing {name!r}")
            upper = token.upper()
            if token == "}":
                return
            if is_end:
                raise tokens.error(f"unexpected {token!r} inside the End Site of {names[parent]!r}", token_line)
            if upper == "JOINT":
                child_name = " ".join(tokens.rest_of_line(token_line)).rstrip("{").strip()
                if child_name.endswith("{"):
                    child_name = child_name[:-1].strip()
                if not child_name:
                    raise tokens.error("JOINT without a name", token_line)
                _unread_brace(tokens, token_line)
                parse_node(index, token_line, False, child_name)
            elif upper == "END":
                rest = tokens.rest_of_line(token_line)
                if not rest or rest[0].lower() != "site":
                    raise tokens.error("expected 'End Site'", token_line)
                _unread_brace(tokens, token_line)
                parse_node(index, token_line, True, f"{name}_End")
            else:
                raise tokens.error(f"unexpected {token!r} in the hierarchy of {name!r}", token_line)

    root_token, root_line = tokens.next("ROOT")
    if root_token.upper() != "ROOT":
        raise tokens.error(f"expected 'ROOT', found {root_token!r}", root_line)
    root_name = " ".join(tokens.rest_of_line(root_line)).rstrip("{").strip()
    if not root_name:
        raise tokens.error("ROOT without a name", root_line)
    _unread_brace(tokens, root_line)
    parse_node(-1, root_line, False, root_name)
    if tokens.peek() is not None:
        token, token_line = tokens.next("")
        if token.upper() == "ROOT":
            raise tokens.error("more than one ROOT is not supported", token_line)
        raise tokens.error(f"unexpected {token!r} after the hierarchy", token_line)

    frame_time, motion = _parse_motion(path, text, found.end(), motion_line, n_channels)
    return Bvh(path=path, names=names, parents=np.array(parents, dtype=int),
               offsets=np.array(offsets, dtype=float).reshape(-1, 3),
               is_end_site=np.array(end_site, dtype=bool), channels=channels,
               channel_start=np.array(channel_start, dtype=int), frame_time=frame_time, motion=motion)


def _unread_brace(tokens: _Tokens, line: int) -> None:
    """``rest_of_line`` may have swallowed a ``{`` written on the JOINT line: put it back."""
    previous = tokens.items[tokens.pos - 1] if tokens.pos else None
    if previous is not None and previous[1] == line and previous[0].endswith("{"):
        if previous[0] == "{":
            tokens.pos -= 1
        else:  # "Name{" glued together
            tokens.items.insert(tokens.pos, ("{", line))


def _next_line(text: str, pos: int, number: int) -> tuple[str, int, int]:
    """The next non-blank line at or after ``pos``: (stripped line, its 1-based number, position after it)."""
    while pos < len(text):
        stop = text.find("\n", pos)
        stop = len(text) if stop < 0 else stop
        number += 1
        line = text[pos:stop].strip()
        pos = stop + 1
        if line:
            return line, number, pos
    return "", number, pos


def _parse_motion(path: str, text: str, pos: int, motion_line: int,
                  n_channels: int) -> tuple[float, np.ndarray]:
    """Frame count, frame time and the (F, C) values after the MOTION keyword at ``pos``."""
    pos = text.find("\n", pos)
    pos = len(text) if pos < 0 else pos + 1
    number = motion_line + 1                                    # 1-based number of the MOTION line
    values = []
    for label in ("Frames:", "Frame Time:"):
        line, number, pos = _next_line(text, pos, number)
        if not line:
            raise InputError(f"{path}: file ends before '{label}'")
        if not line.lower().replace(" ", "").startswith(label.lower().replace(" ", "")):
            raise InputError(f"{path}, line {number}: expected '{label}', found {line[:40]!r}")
        values.append((line.split(":", 1)[1].strip(), number))
    (count_text, count_line), (time_text, time_line) = values
    try:
        n_frames = int(count_text)
    except ValueError:
        raise InputError(f"{path}, line {count_line}: frame count is not an integer: {count_text!r}") from None
    if n_frames < 1:
        raise InputError(f"{path}, line {count_line}: the file has no frames (Frames: {n_frames})")
    try:
        frame_time = float(time_text)
    except ValueError:
        raise InputError(f"{path}, line {time_line}: frame time is not a number: {time_text!r}") from None
    if not np.isfinite(frame_time) or frame_time <= 0:
        raise InputError(f"{path}, line {time_line}: frame time must be positive, got {time_text!r}")
    data = text[pos:]
    if n_channels == 0:
        if data.strip():
            _raise_motion_error(path, data, number, n_frames, 0)
        return frame_time, np.zeros((n_frames, 0))
    # Fast path: one C-level pass over all numbers.  The data is accepted when it holds exactly
    # F x C finite numbers and nothing else; anything else is re-read line by line for a precise error.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            flat = np.fromstring(data, sep=" ")
        except (ValueError, DeprecationWarning):
            flat = None
    if flat is not None and flat.size == n_frames * n_channels and np.all(np.isfinite(flat)):
        return frame_time, flat.reshape(n_frames, n_channels)
    _raise_motion_error(path, data, number, n_frames, n_channels)
    raise AssertionError("unreachable")  # pragma: no cover


def _raise_motion_error(path: str, data: str, line_before: int, n_frames: int, n_channels: int) -> None:
    frame = 0
    for offset, raw in enumerate(data.split("\n"), start=1):
        parts = raw.split()
        if not parts:
            continue
        number = line_before + offset
        if frame >= n_frames:
            raise InputError(f"{path}, line {number}: more frame lines than 'Frames: {n_frames}'")
        if len(parts) != n_channels:
            raise InputError(f"{path}, line {number}: frame {frame} has {len(parts)} values, "
                             f"the hierarchy declares {n_channels} channels")
        for part in parts:
            try:
                value = float(part)
            except ValueError:
                raise InputError(f"{path}, line {number}: frame {frame} has a non-number {part!r}") from None
            if not np.isfinite(value):
                raise InputError(f"{path}, line {number}: frame {frame} has a non-finite value {part!r}")
        frame += 1
    if frame < n_frames:
        raise InputError(f"{path}: 'Frames: {n_frames}' but only {frame} frame lines follow")
    raise InputError(f"{path}: unreadable motion data")


def up_axis(bvh: Bvh, frame: int = 0) -> tuple[int, float]:
    """The axis the figure stands along, as (axis 0/1/2, sign +1/-1).

    Why from the tree and not a fixed rule: files are Y-up or Z-up.  Below
    the first node with several branches (the hips) the subtree with the
    most leaves is the upper body (arms + head), the others are legs; "up"
    is from the legs' centroid to the upper body's centroid.  Uses the posed
    frame ``frame`` (some files, e.g. Bandai Namco, have no meaningful rest
    pose).
    """
    positions = bvh.world_positions(slice(frame, frame + 1))[0]
    hub = 0
    while len(bvh.children[hub]) == 1:
        hub = bvh.children[hub][0]
    subtrees = [_subtree(bvh, c) for c in bvh.children[hub]]
    if len(subtrees) < 2:
        raise InputError(f"{bvh.path}: cannot tell up from down: the skeleton has no branching hips")
    leaf_counts = [sum(1 for j in s if not bvh.children[j]) for s in subtrees]
    upper = int(np.argmax(leaf_counts))
    upper_centroid = positions[subtrees[upper]].mean(axis=0)
    lower = np.concatenate([s for i, s in enumerate(subtrees) if i != upper])
    direction = upper_centroid - positions[lower].mean(axis=0)
    axis = int(np.argmax(np.abs(direction)))
    return axis, float(np.sign(direction[axis]) or 1.0)


def _subtree(bvh: Bvh, j: int) -> list[int]:
    out, stack = [], [j]
    while stack:
        k = stack.pop()
        out.append(k)
        stack.extend(bvh.children[k])
    return out


def format_bvh(bvh: Bvh, precision: int = 6) -> str:
    """BVH text for ``bvh`` (the inverse of :func:`parse_bvh`; End Sites written as End Sites).

    Why: tests and benchmarks build skeletons in code (LaFAN1, Mixamo, Z-up
    variants) and need them as files, and it gives a round-trip check of
    the reader.
    """
    lines = ["HIERARCHY"]

    def emit(j: int, depth: int) -> None:
        pad = "\t" * depth
        off = " ".join(f"{v:.{precision}f}" for v in bvh.offsets[j])
        if bvh.is_end_site[j]:
            lines.extend([f"{pad}End Site", pad + "{", f"{pad}\tOFFSET {off}", pad + "}"])
            return
        lines.append(f"{pad}{'ROOT' if bvh.parents[j] < 0 else 'JOINT'} {bvh.names[j]}")
        lines.append(pad + "{")
        lines.append(f"{pad}\tOFFSET {off}")
        if bvh.channels[j]:
            names = " ".join(c[0].upper() + c[1:] for c in bvh.channels[j])
            lines.append(f"{pad}\tCHANNELS {len(bvh.channels[j])} {names}")
        for child in bvh.children[j]:
            emit(child, depth + 1)
        lines.append(pad + "}")

    emit(0, 0)
    lines += ["MOTION", f"Frames: {bvh.n_frames}", f"Frame Time: {bvh.frame_time:.8f}"]
    lines.extend(" ".join(f"{v:.{precision}f}" for v in row) for row in bvh.motion)
    return "\n".join(lines) + "\n"


def make_bvh(tree, motion=None, frame_time: float = 1.0 / 30.0, rotation_order: str = "ZXY",
             path: str = "<built>") -> Bvh:
    """A :class:`Bvh` from ``tree`` = [(name, parent name or None, (x, y, z)), ...] in parent-first order.

    A name ending in ``"_End"`` whose parent has no other node of that name
    becomes an End Site.  The root gets 6 channels, other joints 3 rotation
    channels in ``rotation_order``.  ``motion`` defaults to one frame of zeros.
    """
    names = [t[0] for t in tree]
    index = {name: i for i, name in enumerate(names)}
    parents = np.array([-1 if t[1] is None else index[t[1]] for t in tree], dtype=int)
    offsets = np.array([t[2] for t in tree], dtype=float)
    is_end = np.array([name.endswith("_End") and parents[i] >= 0 for i, name in enumerate(names)], dtype=bool)
    rotations = tuple(f"{axis.lower()}rotation" for axis in rotation_order)
    channels, starts, n_channels = [], [], 0
    for i in range(len(names)):
        ch: tuple[str, ...] = ()
        if not is_end[i]:
            ch = ("xposition", "yposition", "zposition") + rotations if parents[i] < 0 else rotations
        channels.append(ch)
        starts.append(n_channels)
        n_channels += len(ch)
    if motion is None:
        motion = np.zeros((1, n_channels))
        motion[0, :3] = offsets[0]
    motion = np.asarray(motion, dtype=float)
    if motion.shape[1] != n_channels:
        raise ValueError(f"motion has {motion.shape[1]} columns, the tree needs {n_channels}")
    return Bvh(path=path, names=names, parents=parents, offsets=offsets, is_end_site=is_end, channels=channels,
               channel_start=np.array(starts, dtype=int), frame_time=frame_time, motion=motion)
