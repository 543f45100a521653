"""An animator's correction: one foot held still in the world over a span of frames.

Why: the motion cleanup holds the ankles it finds low and slow in the solved motion
(:mod:`.contacts`), but where the solve let a standing foot slide (most of all along the line of
sight, which one picture says least about, and around a camera move the solve misjudged) no
low-and-slow rule finds the contact, and the foot skates. The animator sees where the foot stands;
this holds it there, the way the automatic lock does: the ankle pinned to the median of where the solve
put it over the span, the leg bent to reach it (two-bone IK: the hip stays, thigh and shin keep their
lengths, the knee stays in the plane it bent in), the offset eased in and out over ``blend_s`` on the
frames either side so the foot neither pops in nor out.

The ankle leaves its tracked place in the picture by as much as it is moved (the report gives the
largest move); nothing but the leg's knee and ankle moves, unless the place is out of the leg's reach by
:data:`REACH_WARN_M`: the solve let the body drift away from the foot, and the whole figure is first slid back
along its line of sight (:func:`_slid_towards`).

:func:`stance_span` proposes the span around a frame: the frames the solve names this foot the standing one.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError
from ..result import Estimate
from ..runs import runs
from ..skeleton import FEET
from .contacts import ContactSettings
from .foot_lock import LEGS, lock_feet, smoothstep

#: the ease either side of the span (seconds): the automatic lock's
#: (:attr:`core.motion_cleanup.CleanupSettings.blend_s`)
BLEND_S = 0.1
#: frame rate assumed for the ease when the estimate does not record its own
DEFAULT_FPS = 30.0
#: :func:`stance_span` offers the frames around a frame on which the solve names that foot the standing one
#: (each frame's ``stance``) and its ankle is as low beside the other as a contact the automatic lock starts
#: (:attr:`.contacts.ContactSettings.on_height`), less :data:`OFFER_TRIM_S` at either end (the solve's stance
#: runs on into the neighbouring double support). Chosen on the tune half of ``bench/plant_bench.py --offered``
#: (18 cases a scenario; an animator planting each offer as it comes, at the middle frame of every true contact
#: that slid): the detector scenario's median case 108 -> 42 mm/s over the truth's (mean case 499 -> 456), the
#: still camera's mean case 280 -> 160, against 108 -> 96 and 280 -> 280 with the automatic contacts' release
#: rule (no higher than 0.09 body heights and no faster than 0.3 a second: a sliding foot is too fast for it).
#: The stance run alone: untrimmed 108 -> 86, trimmed by 0.05 s 108 -> 42 (the still camera's mean case 280 ->
#: 184, its per-frame error +0.27 mm against +0.17), by 0.1 s 108 -> 91. On the report half the offers did little
#: (paper's schedule 208 -> 192, detector 274 -> 274): the frames are the animator's to set from the footage
OFFER_LOW = ContactSettings().on_height
OFFER_TRIM_S = 0.05

#: a place farther than this (metres) beyond the leg's reach on some frame: the body moves away from where the
#: foot is held (the solve's depth drifting, a span too long, or a foot that really moved), and bending the leg
#: alone pulls it straight towards the place with the foot still sliding by as much. Then the body is slid
#: back first (:func:`_slid_towards`), and if the leg still cannot reach, the user is warned. On the tune half
#: of ``bench/plant_bench.py`` (the leg alone, before the slide was added), an animator undoing the plants
#: warned of at 2 / 5 / 10 / 20 cm kept 62 / 75 / 80 / 87 of 96 and left the moving cameras' mean case at 103 /
#: 90 / 87 / 83 mm/s over the truth's (paper's schedule), 341 / 329 / 329 / 280 (detector's errors), per-frame
#: error +0.2 / +0.3 / +0.3 / +0.3 and +0.05 / +0.1 / +0.1 / +0.3 mm: warned from 5 cm, where a leg pulled
#: straight is plain to see
REACH_WARN_M = 0.05

SIDES = {"l": 0, "r": 1}
SIDE_NAMES = {"l": "left", "r": "right"}


def _side(foot: str) -> int:
    key = {"left": "l", "right": "r", "l_ankle": "l", "r_ankle": "r"}.get(foot, foot)
    if key not in SIDES:
        raise InputError(f"no foot {foot!r}: give l or r (left or right)")
    return SIDES[key]


def _key(foot: str) -> str:
    return "lr"[_side(foot)]


def _joints(est: Estimate, first: int, last: int) -> np.ndarray:
    """(last - first + 1, 17, 3) 3D joints of frames ``first``..``last`` in frame 0's axes."""
    missing = [i for i in range(first, last + 1) if est.frames[i].joints_3d is None]
    if missing:
        raise InputError(f"the estimate has no 3D joints on frame {missing[0]}: run the joint method")
    return np.array([est.frames[i].joints_3d for i in range(first, last + 1)], dtype=float)


def _check_span(est: Estimate, first: int, last: int) -> None:
    n = len(est.frames)
    if not (0 <= first <= last < n):
        raise InputError(f"frames {first}-{last} are not in the estimate's 0-{n - 1}")


def _fps(est: Estimate) -> float:
    return float((est.diagnostics or {}).get("fps") or DEFAULT_FPS)


def _with_3d(est: Estimate, first: int, last: int, reach: int) -> tuple[int, int]:
    """(lo, hi): frames ``first``..``last`` widened by up to ``reach`` frames either side over frames that
    have 3D joints."""
    lo, hi = first, last
    while lo > max(0, first - reach) and est.frames[lo - 1].joints_3d is not None:
        lo -= 1
    while hi < min(len(est.frames) - 1, last + reach) and est.frames[hi + 1].joints_3d is not None:
        hi += 1
    return lo, hi


def _slid_towards(joints: np.ndarray, side: int, a: int, b: int, blend: int) -> tuple[np.ndarray, float]:
    """(``joints`` with the whole figure slid along the pelvis' line of sight on frames ``a``..``b`` just far
    enough that the leg reaches the ankle's median place over them, eased in and out over ``blend`` frames
    either side; the largest slide in metres).

    Why: where the solve lets a standing body drift in depth (a zoom read as the person coming nearer) the
    place the foot stood is out of the leg's reach, and bending the leg alone pulls it straight towards it.
    The drift is the solve's depth, so the body goes back along its line of sight: the pelvis keeps its place
    in the picture and the figure its shape (a rigid move), and the per-frame pose is unchanged."""
    hip, knee, ankle = LEGS[side]
    seg = slice(a, b + 1)
    place = np.median(joints[seg, ankle], axis=0)
    reach = (np.linalg.norm(joints[seg, knee] - joints[seg, hip], axis=1)
             + np.linalg.norm(joints[seg, ankle] - joints[seg, knee], axis=1) - 1e-3)
    ray = joints[:, 0] / np.linalg.norm(joints[:, 0], axis=1, keepdims=True)
    h = joints[seg, hip] - place                     # the hip from the place; |h + t ray| <= reach, |t| least
    hu = np.sum(h * ray[seg], axis=1)
    far = np.sum(h * h, axis=1) - reach ** 2
    root = np.sqrt(np.maximum(hu ** 2 - far, 0.0))
    near = np.where(np.abs(-hu - root) < np.abs(-hu + root), -hu - root, -hu + root)
    t = np.zeros(len(joints))
    t[seg] = np.where(far <= 0.0, 0.0, np.where(hu ** 2 >= far, near, -hu))   # out of reach on the ray: nearest
    for edge, idx in ((a, np.arange(max(0, a - blend), a)), (b, np.arange(b + 1, min(len(t), b + blend + 1)))):
        t[idx] = (1.0 - smoothstep(np.abs(idx - edge) / (blend + 1.0))) * t[edge]
    return joints + (t[:, None] * ray)[:, None, :], float(np.abs(t).max())


def plant_foot(est: Estimate, foot: str, first: int, last: int, *, blend_s: float = BLEND_S) -> tuple[Estimate, dict]:
    """``est`` with the ``foot`` (``"l"`` or ``"r"``) held still on frames ``first`` to ``last`` (0-based,
    inclusive), and a report: ``frames`` held, ``place`` (the ankle's place, metres, frame 0's axes),
    ``slide_m`` (how far the solve's ankle strayed from its median over the span), ``largest_move_m`` (of the
    ankle, eases included), ``unreached_m`` (how far the place lay beyond the leg's reach on its worst frame),
    ``body_slide_m`` (how far the whole figure was slid along its line of sight first, where the leg alone could
    not reach by :data:`REACH_WARN_M`: :func:`_slid_towards`; 0 if not).

    The frames either side that the ease reaches need 3D joints too; where the estimate has none there the
    ease stops short. Returns a new estimate (``est`` is not changed) whose ``diagnostics["planted_feet"]``
    lists every such correction made to it, this one last."""
    side = _side(foot)
    _check_span(est, first, last)
    fps = _fps(est)
    blend = max(0, int(round(blend_s * fps)))
    lo, hi = _with_3d(est, first, last, blend)                  # the ease's frames that have 3D joints
    old = _joints(est, lo, hi)                                  # one line if the span has a frame without 3D
    contacts = np.zeros((hi - lo + 1, 2), dtype=bool)
    contacts[first - lo:last - lo + 1, side] = True
    new, lock = lock_feet(old, contacts, fps, blend_s)
    body = 0.0
    if lock["unreached_m"] > REACH_WARN_M:             # the body drifted away: slide it back, then hold the foot
        slid, shift = _slid_towards(old, side, first - lo, last - lo, blend)
        again, held = lock_feet(slid, contacts, fps, blend_s)
        if held["unreached_m"] < lock["unreached_m"]:
            new, lock, body = again, held, shift
    ankle = FEET[_key(foot)]
    span = old[first - lo:last - lo + 1, ankle]
    place = np.median(new[first - lo:last - lo + 1, ankle], axis=0)
    moved = np.linalg.norm(new[:, ankle] - old[:, ankle], axis=1)
    frames = list(est.frames)
    for k in np.flatnonzero(np.any(new != old, axis=(1, 2))):
        frames[lo + k] = dataclasses.replace(frames[lo + k], joints_3d=new[k].tolist())
    report = {"foot": _key(foot), "first": first, "last": last, "frames": last - first + 1,
              "place": [float(v) for v in place], "slide_m": float(np.max(np.linalg.norm(span - place, axis=1))),
              "largest_move_m": float(moved.max()), "unreached_m": float(lock["unreached_m"]), "body_slide_m": body}
    diagnostics = dict(est.diagnostics or {})
    diagnostics["planted_feet"] = list(diagnostics.get("planted_feet", [])) + [report]
    return dataclasses.replace(est, frames=frames, diagnostics=diagnostics), report


def reach_warning(report: dict) -> str:
    """What a plant whose place lies beyond the leg's reach (``report["unreached_m"]`` over :data:`REACH_WARN_M`)
    leaves, for the user: a leg pulled straight towards a place the body moved away from."""
    return (f"the held place lay up to {100 * report['unreached_m']:.0f} cm beyond the leg's reach (the body moves "
            "away from it over these frames): the leg is pulled straight towards it; plant fewer frames or undo")


def stance_span(est: Estimate, foot: str, frame: int) -> tuple[int, int]:
    """(first, last): the frames around ``frame`` on which the solve names the ``foot`` the standing one and its
    ankle is low beside the other (:data:`OFFER_LOW` body heights, up being the estimate's world Z), less
    :data:`OFFER_TRIM_S` at either end: the span :func:`plant_foot` is offered. One line (``InputError``) if
    that foot is not standing so on ``frame``."""
    side = _side(foot)
    key = _key(foot)
    _check_span(est, frame, frame)
    world = (est.diagnostics or {}).get("world_from_cam0")
    if world is None:
        raise InputError("the estimate has no floor (world_from_cam0): give the frames")
    lo, hi = _with_3d(est, frame, frame, len(est.frames))
    w = np.asarray(world, dtype=float)
    ankles = (_joints(est, lo, hi) @ w[:3, :3].T + w[:3, 3])[:, [FEET["l"], FEET["r"]]]
    z = ankles[..., 2]
    height_m = float(est.height_m) if est.height_m else 1.75
    low = (z[:, side] - z.min(axis=1)) / height_m <= OFFER_LOW
    named = np.array([est.frames[i].stance == key for i in range(lo, hi + 1)])
    standing = named & low
    k = frame - lo
    trim = int(round(OFFER_TRIM_S * _fps(est)))
    a, end = next(((a, end) for a, end in runs(standing) if a <= k < end), (k, k))
    if not a + trim <= k < end - trim:               # not standing on the frame, or in the trimmed ends
        raise InputError(f"the {SIDE_NAMES[key]} foot is not standing on frame {frame}: give the frames")
    return int(lo + a + trim), int(lo + end - 1 - trim)
