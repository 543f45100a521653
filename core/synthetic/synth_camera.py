"""The virtual camera's schedule: still spells and smooth pans, tilts, zooms, rolls.

Peng & Li (2006, sections 3.2 and 5) film their synthetic figure with a camera
on a tripod that stays still for at least 1 s between motions, and performs one
motion at a time for at least 0.5 s: a pan, a tilt, a pan+tilt ("directional
rotating") or a zoom.  This module writes such schedules, and (beyond the
paper) simultaneous rotation + zoom, a slow roll, and schedules with no still
spell between motions (``continuous=True``).

A schedule is a list of :class:`Spell` covering frames ``0 .. n_frames-1``
without gaps.  ``end`` is INCLUSIVE (the last frame of the spell), so spells
read ``[0, 44], [45, 70], ...``.  A motion spell's ``params`` are the CHANGE it
makes, in degrees for ``pan_deg`` / ``tilt_deg`` / ``roll_deg`` and as a focal
ratio (new / old) for ``zoom``.  Within a spell of n frames the change follows
the cosine ease-in/ease-out profile ``p(k) = (1 - cos(pi k / n)) / 2`` for
k = 1..n, so every frame of a motion spell differs from its predecessor
(``camera_moving`` is exactly the motion spells' frames), the last frame
reaches the full change, and speed is zero at both ends of every spell.
Angles add up; the focal length is interpolated geometrically.

Per-frame camera: ``R_i = pan_tilt_roll_matrix(pan_i, tilt_i, roll_i)`` of
:mod:`core.camera` (``X_i = R_i X_0``, ``R_0 = I``) and ``f_i`` in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..camera import pan_tilt_roll_matrix
from ..errors import InputError

CAMERA_KINDS: tuple[str, ...] = ("still", "pan", "tilt", "pan_tilt", "zoom", "rotate_zoom", "roll")
#: The kinds of the paper's experiment (one camera motion at a time).
PAPER_KINDS: tuple[str, ...] = ("pan", "tilt", "pan_tilt", "zoom")

#: Minimum durations from the paper's assumptions, seconds.
MIN_STILL_S = 1.0
MIN_MOTION_S = 0.5
#: The still spell that closes a clip is not *between* motions; half a second is enough.
MIN_CLOSING_STILL_S = 0.5
#: Ranges the generator draws from (seconds); inside the paper's limits.
STILL_RANGE_S = (1.0, 2.0)
MOTION_RANGE_S = (0.6, 1.5)
ROLL_RANGE_S = (1.5, 2.5)        # rolls are slow

#: Realistic amplitudes of one motion (degrees, or focal ratio for zooms).
PAN_RANGE_DEG = (5.0, 20.0)
TILT_RANGE_DEG = (3.0, 8.0)
ROLL_RANGE_DEG = (2.0, 5.0)
ZOOM_RATIO_RANGE = (1.15, 1.40)
#: Bounds on the accumulated state, so the camera keeps looking at the scene.
PAN_LIMIT_DEG = 20.0
TILT_LIMIT_DEG = 8.0
ROLL_LIMIT_DEG = 6.0
FOCAL_RATIO_LIMITS = (1.0, 1.6)   # focal / frame-0 focal: frame 0 is the widest view


@dataclass
class Spell:
    """One stretch of the schedule: frames ``start .. end`` (inclusive)."""

    start: int
    end: int
    kind: str
    params: dict = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return self.end - self.start + 1

    @property
    def moving(self) -> bool:
        return self.kind != "still"

    def to_dict(self) -> dict:
        return {"start": int(self.start), "end": int(self.end), "kind": self.kind,
                "params": {k: float(v) for k, v in self.params.items()}}

    @classmethod
    def from_dict(cls, doc, where: str = "") -> Spell:
        if not isinstance(doc, dict):
            raise InputError(f"{where}spell must be an object, got {doc!r}")
        start, end, kind = doc.get("start"), doc.get("end"), doc.get("kind")
        if not (isinstance(start, int) and isinstance(end, int) and not isinstance(start, bool)
                and not isinstance(end, bool) and 0 <= start <= end):
            raise InputError(f"{where}spell needs integer 0 <= start <= end, got {doc!r}")
        if kind not in CAMERA_KINDS:
            raise InputError(f"{where}unknown spell kind {kind!r}; expected one of {list(CAMERA_KINDS)}")
        params = doc.get("params", {})
        if not isinstance(params, dict) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in params.values()):
            raise InputError(f"{where}spell params must map names to finite numbers, got {params!r}")
        return cls(start, end, kind, {str(k): float(v) for k, v in params.items()})


def check_kinds(kinds) -> tuple[str, ...]:
    """Validate camera kinds (a sequence or a comma-separated string)."""
    if isinstance(kinds, str):
        kinds = [k.strip() for k in kinds.split(",") if k.strip()]
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in CAMERA_KINDS]
    if bad:
        raise InputError(f"unknown camera motion kind(s) {bad}; choose from {list(CAMERA_KINDS)}")
    return kinds


def _frames(seconds: float, fps: float) -> int:
    return max(1, int(math.ceil(seconds * fps - 1e-9)))


class _Drawer:
    """Draws amplitudes that keep the accumulated camera state within its limits."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng
        self.pan = self.tilt = self.roll = 0.0
        self.focal_ratio = 1.0

    def _angle(self, current: float, lo: float, hi: float, limit: float) -> float:
        # Prefer heading back towards the start (a camera operator re-centres), but not always.
        options = [s for s in (1.0, -1.0) if abs(current + s * lo) <= limit + 1e-9]
        if not options:
            options = [-math.copysign(1.0, current)]
        if len(options) == 2 and abs(current) > 1e-9 and self.rng.random() < 0.75:
            sign = -math.copysign(1.0, current)
        else:
            sign = options[int(self.rng.integers(len(options)))]
        room = limit - sign * current
        top = max(lo, min(hi, room))
        return sign * float(self.rng.uniform(lo, top))

    def _zoom(self) -> float:
        lo, hi = ZOOM_RATIO_RANGE
        f_lo, f_hi = FOCAL_RATIO_LIMITS
        can_in = self.focal_ratio * lo <= f_hi + 1e-9
        can_out = self.focal_ratio / lo >= f_lo - 1e-9
        zoom_in = can_in and (not can_out or self.rng.random() < 0.5)
        if zoom_in:
            r = float(self.rng.uniform(lo, max(lo, min(hi, f_hi / self.focal_ratio))))
        else:
            r = 1.0 / float(self.rng.uniform(lo, max(lo, min(hi, self.focal_ratio / f_lo))))
        return r

    def params(self, kind: str) -> dict:
        p: dict[str, float] = {}
        if kind in ("pan", "pan_tilt", "rotate_zoom"):
            p["pan_deg"] = self._angle(self.pan, *PAN_RANGE_DEG, PAN_LIMIT_DEG)
        if kind in ("tilt", "pan_tilt", "rotate_zoom"):
            p["tilt_deg"] = self._angle(self.tilt, *TILT_RANGE_DEG, TILT_LIMIT_DEG)
        if kind == "roll":
            p["roll_deg"] = self._angle(self.roll, *ROLL_RANGE_DEG, ROLL_LIMIT_DEG)
        if kind in ("zoom", "rotate_zoom"):
            p["zoom"] = self._zoom()
        self.pan += p.get("pan_deg", 0.0)
        self.tilt += p.get("tilt_deg", 0.0)
        self.roll += p.get("roll_deg", 0.0)
        self.focal_ratio *= p.get("zoom", 1.0)
        return p


def make_schedule(n_frames: int, fps: float, kinds=("pan", "tilt", "zoom"), seed: int = 0, *,
                  continuous: bool = False) -> list[Spell]:
    """A random camera schedule covering ``n_frames`` frames, deterministic from ``seed``.

    Rules (paper mode): a still spell of 1.0-2.0 s opens the clip; then motion
    spells of 0.6-1.5 s (rolls 1.5-2.5 s) alternate with still spells of
    1.0-2.0 s; the clip ends with a still spell that absorbs the leftover
    frames.  Durations are whole frames: a still lasts at least ceil(1.0 fps)
    frames, a motion at least ceil(0.5 fps), and the closing still (which is
    not between motions) at least ceil(0.5 fps).  Near the end a drawn
    duration is shortened (a motion down to 0.5 s, the still before it down
    to 1 s) when that leaves room for one more motion plus the closing still;
    the opening still is shortened to 1 s for short clips likewise.  Clips
    shorter than ceil(fps) + 2 ceil(0.5 fps) frames are one still spell.  Motion
    kinds are taken from ``kinds`` in shuffled rounds so each kind appears.
    With ``continuous=True`` the motions follow each other with no still spell
    in between (after the opening still), and the last motion absorbs a
    leftover shorter than 0.5 s.
    Amplitudes: pans 5-20 deg, tilts 3-8 deg, rolls 2-5 deg, zooms change the
    focal length by 15-40 %; the accumulated pan stays within +-20 deg, tilt
    +-8 deg, roll +-6 deg, and the focal length within 1.0-1.6 x frame 0's
    (frame 0 is the widest view).  "still" in ``kinds`` is ignored.
    """
    kinds = check_kinds(kinds)
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a positive number, got {fps!r}")
    n_frames = int(n_frames)
    if n_frames < 1:
        raise InputError(f"a schedule needs at least 1 frame, got {n_frames}")
    motions = [k for k in dict.fromkeys(kinds) if k != "still"]
    rng = np.random.default_rng([int(seed), 0x5C4ED])
    drawer = _Drawer(rng)
    still_min = _frames(MIN_STILL_S, fps)
    motion_min = _frames(MIN_MOTION_S, fps)
    close_min = _frames(MIN_CLOSING_STILL_S, fps)

    def still_len() -> int:
        return max(still_min, _frames(rng.uniform(*STILL_RANGE_S), fps))

    def motion_len(kind: str) -> int:
        lo, hi = ROLL_RANGE_S if kind == "roll" else MOTION_RANGE_S
        return max(motion_min, _frames(rng.uniform(lo, hi), fps))

    spells: list[Spell] = []
    first = min(n_frames, still_len())
    if n_frames - first < motion_min + (0 if continuous else close_min):
        first = min(n_frames, still_min)        # a short clip: keep room for one motion if possible
    spells.append(Spell(0, first - 1, "still"))
    pos = first
    queue: list[str] = []
    while pos < n_frames and motions:
        if not queue:
            queue = [motions[i] for i in rng.permutation(len(motions))]
            if len(queue) > 1 and len(spells) > 1 and queue[0] == spells[-1 if continuous else -2].kind:
                queue.append(queue.pop(0))     # no kind twice in a row across rounds
        kind = queue.pop(0)
        length = motion_len(kind)
        after = 0 if continuous else close_min
        length = min(length, n_frames - pos - after)      # shorten a motion that would not fit
        if length < motion_min:
            break
        if continuous and n_frames - (pos + length) < motion_min:
            length = n_frames - pos           # the last motion absorbs the leftover
        spells.append(Spell(pos, pos + length - 1, kind, drawer.params(kind)))
        pos += length
        if not continuous:
            gap = still_len()
            if n_frames - (pos + gap) < motion_min + close_min:
                gap = still_min                # make room for one more motion if a short still allows it
                if n_frames - (pos + gap) < motion_min + close_min:
                    gap = n_frames - pos       # too little room for another motion: the closing still
            spells.append(Spell(pos, pos + gap - 1, "still"))
            pos += gap
    if pos < n_frames:
        last = spells[-1]
        if last.kind == "still":
            last.end = n_frames - 1
        else:
            spells.append(Spell(pos, n_frames - 1, "still"))
    return spells


def check_schedule(spells: list[Spell], n_frames: int) -> list[Spell]:
    """Validate that ``spells`` cover ``0 .. n_frames-1`` in order without gaps."""
    if not spells:
        raise InputError("camera schedule is empty")
    pos = 0
    for s in spells:
        if s.kind not in CAMERA_KINDS:
            raise InputError(f"unknown spell kind {s.kind!r} at frames {s.start}-{s.end}")
        if s.start != pos or s.end < s.start:
            raise InputError(f"camera schedule has a gap or overlap at frame {pos} (spell {s.start}-{s.end})")
        pos = s.end + 1
    if pos != n_frames:
        raise InputError(f"camera schedule covers {pos} frames, the motion has {n_frames}")
    return spells


def ease(n: int) -> np.ndarray:
    """Cosine ease-in/ease-out progress for the n frames of a spell (last = 1)."""
    k = np.arange(1, n + 1, dtype=float)
    return 0.5 * (1.0 - np.cos(np.pi * k / n))


def camera_states(spells: list[Spell], n_frames: int, focal_mm: float):
    """Per-frame accumulated (pan, tilt, roll) degrees (F, 3) and focal lengths (F,) mm."""
    check_schedule(spells, n_frames)
    angles = np.zeros((n_frames, 3))
    log_f = np.full(n_frames, math.log(focal_mm))
    cur = np.zeros(3)
    cur_log_f = math.log(focal_mm)
    for s in spells:
        sl = slice(s.start, s.end + 1)
        delta = np.array([s.params.get("pan_deg", 0.0), s.params.get("tilt_deg", 0.0), s.params.get("roll_deg", 0.0)])
        d_log_f = math.log(s.params.get("zoom", 1.0))
        p = ease(s.n_frames) if s.moving else np.ones(s.n_frames)
        angles[sl] = cur + p[:, None] * delta
        log_f[sl] = cur_log_f + p * d_log_f
        cur = cur + delta
        cur_log_f += d_log_f
    return angles, np.exp(log_f)


def camera_rotations(angles_deg: np.ndarray) -> np.ndarray:
    """(F, 3, 3) rotations ``R_i`` (``X_i = R_i X_0``) from accumulated pan/tilt/roll."""
    a = np.asarray(angles_deg, dtype=float)
    return pan_tilt_roll_matrix(a[:, 0], a[:, 1], a[:, 2])


def moving_mask(spells: list[Spell], n_frames: int) -> np.ndarray:
    """(F,) bool: the camera changed since the previous frame (motion spells)."""
    out = np.zeros(n_frames, dtype=bool)
    for s in spells:
        changes = any(abs(v) > 0 for k, v in s.params.items() if k != "zoom") or s.params.get("zoom", 1.0) != 1.0
        if s.moving and changes:
            out[s.start:s.end + 1] = True
    return out
