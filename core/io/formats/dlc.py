"""DeepLabCut CSV: header rows ``scorer`` / ``bodyparts`` / ``coords`` then one row per frame.

Columns come in ``x, y, likelihood`` triples per body part (labelled-data
files with only ``x, y`` pairs get confidence 1).  Multi-animal files (an
extra ``individuals`` header row) are read for the individual with the
largest summed likelihood over the clip.  Rows are frames in file order.
An empty cell (how pandas writes NaN) means the part is missing in that
frame; a literal ``nan`` is refused like every other non-number.

Body-part names are matched case-insensitively, ignoring ``_``, ``-``,
``.`` and spaces, against :data:`BODY_PART_NAMES` (e.g. ``LeftShoulder``,
``shoulder_l``, ``l_shoulder``, ``Shoulder.L`` all mean the left shoulder).
Parts with other names are ignored (listed in ``meta["ignored_parts"]``).
DeepLabCut stores no frame rate or image size: both come from the arguments.
"""

from __future__ import annotations

import re

import numpy as np

from ...errors import InputError
from ...tracks import Tracks
from ._canonical import canonical_tracks, choose_fps, choose_image_size
from ._io import check_row_widths, csv_rows, float_column

LABEL = "DeepLabCut CSV"
_COLUMN = {"x": 0, "y": 1, "likelihood": 2}

_SIDED = {
    "shoulder": ("shoulder",), "elbow": ("elbow",), "wrist": ("wrist",), "hip": ("hip",),
    "knee": ("knee",), "ankle": ("ankle",), "ear": ("ear",), "eye": ("eye",),
}
_CENTRAL = {
    "pelvis": ("pelvis", "midhip", "hipcenter", "hipcentre", "hipmid", "root"),
    "spine": ("spine", "midspine", "spinemid", "midback"),
    "thorax": ("thorax", "chest", "sternum", "midshoulder", "shouldercenter", "shouldercentre", "neckbase"),
    "neck": ("neck", "upperneck"),
    "head": ("head", "headtop", "topofhead", "tophead", "crown"),
    "nose": ("nose",),
}


def _build_names() -> dict[str, str]:
    table = {}
    for vocab, names in _CENTRAL.items():
        for name in names:
            table[name] = vocab
    for base, names in _SIDED.items():
        for name in names:
            for side, words in (("l", ("left", "l")), ("r", ("right", "r"))):
                for word in words:
                    table[word + name] = f"{side}_{base}"
                    table[name + word] = f"{side}_{base}"
    return table


#: normalised body-part name -> vocabulary name (canonical joint or face point).
BODY_PART_NAMES: dict[str, str] = _build_names()


def normalise_part(name: str) -> str:
    return re.sub(r"[\s_.\-]+", "", name.lower())


def part_vocabulary(name: str) -> str | None:
    return BODY_PART_NAMES.get(normalise_part(name))


def read_dlc(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    rows = csv_rows(source)
    if rows[0][1][0].lower() != "scorer":
        raise InputError(f"{source}: line {rows[0][0]}: not a DeepLabCut CSV (first header cell must be 'scorer')")
    multi = len(rows) > 1 and rows[1][1][0].lower() == "individuals"
    n_header = 4 if multi else 3
    if len(rows) < n_header:
        raise InputError(f"{source}: header is incomplete (expected rows scorer, "
                         f"{'individuals, ' if multi else ''}bodyparts, coords)")
    labels = ["individuals", "bodyparts", "coords"] if multi else ["bodyparts", "coords"]
    width = len(rows[0][1])
    for (line, cells), label in zip(rows[1:n_header], labels, strict=True):
        if cells[0].lower() != label:
            raise InputError(f"{source}: line {line}: expected the '{label}' header row, got {cells[0]!r}")
        if len(cells) != width:
            raise InputError(f"{source}: line {line}: {len(cells)} cells but the scorer row has {width}")
    individuals = rows[1][1] if multi else [""] * width
    parts, coords = rows[n_header - 2][1], rows[n_header - 1][1]
    groups: dict[tuple[str, str], dict[str, int]] = {}
    for k in range(1, width):
        c = coords[k].lower()
        if c not in ("x", "y", "likelihood"):
            continue
        group = groups.setdefault((individuals[k], parts[k]), {})
        if c in group:
            raise InputError(f"{source}: body part {parts[k]!r} has two '{c}' columns")
        group[c] = k
    for (_, part), group in groups.items():
        if "x" not in group or "y" not in group:
            raise InputError(f"{source}: missing columns: body part {part!r} needs both x and y")
    mapped = {key: part_vocabulary(key[1]) for key in groups}
    ignored = sorted({part for (_, part), v in mapped.items() if v is None})
    names = sorted({v for v in mapped.values() if v is not None})
    if not names:
        raise InputError(f"{source}: no body part name is recognised ({ignored[:8]}); use names such as nose, "
                         "left_shoulder, right_hip (see docs/formats.md)")
    for ind in {i for i, _ in groups}:
        seen: dict[str, str] = {}
        for (i, part), v in mapped.items():
            if i == ind and v is not None:
                if v in seen:
                    raise InputError(f"{source}: body parts {seen[v]!r} and {part!r} both mean {v}")
                seen[v] = part
    data = rows[n_header:]
    if not data:
        raise InputError(f"{source}: no frames after the header")
    n = len(data)
    lines = [line for line, _ in data]
    check_row_widths(data, width, source)
    values: dict[tuple[str, str], np.ndarray] = {}
    for key, group in groups.items():
        if mapped[key] is None:
            continue
        arr = values[key] = np.full((n, 3), np.nan)
        for c, k in group.items():
            arr[:, _COLUMN[c]] = float_column([cells[k] for _, cells in data], lines, source,
                                              f"body part {key[1]!r} {c}", allow_empty=True)
        negative = np.flatnonzero(arr[:, 2] < 0)
        if negative.size:
            raise InputError(f"{source}: line {lines[negative[0]]}: body part {key[1]!r} has a negative likelihood")
        if "likelihood" not in group:
            arr[:, 2] = np.where(np.isfinite(arr[:, :2]).all(axis=1), 1.0, np.nan)
    chosen = ""
    if multi:
        totals = {}
        for (ind, _part), arr in values.items():
            totals[ind] = totals.get(ind, 0.0) + float(np.nansum(arr[:, 2]))
        chosen = max(sorted(totals), key=lambda i: totals[i])
    xy = np.full((n, len(names), 2), np.nan)
    conf = np.zeros((n, len(names)))
    for (ind, part), arr in values.items():
        v = mapped[(ind, part)]
        if ind != chosen:
            continue
        k = names.index(v)
        ok = np.isfinite(arr).all(axis=1)
        xy[ok, k] = arr[ok, :2]
        conf[ok, k] = arr[ok, 2]
    fps = choose_fps(fps, None, LABEL, source)
    image_size = choose_image_size(image_size, None, LABEL, source)
    meta = {"format": "dlc", "scorer": rows[0][1][1] if width > 1 else "", "ignored_parts": ignored,
            "body_parts": {part: v for (_, part), v in mapped.items() if v is not None}}
    if multi:
        meta["individual"] = chosen
    return canonical_tracks(xy, conf, names, fps=fps, image_size=image_size, source=source, meta=meta)
