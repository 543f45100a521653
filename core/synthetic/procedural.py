"""Built-in procedural motions: a walk with turns, a run and a person standing on the spot, no file needed.

Why procedural: the demo, the tests and the benchmarks need a motion whose
truth is exact (rigid figure, known proportions, known foot contacts) and that
ships with the project (the real BVH clips cannot be redistributed).

How a clip is made (all in metres, Y up, floor at y = 0, the figure faces
+Z at heading 0 and its left is ``up x forward``):

1. A curved ground path with smoothly varying curvature (left and right
   turns) is integrated from its heading; the pelvis travels along it at the
   gait speed.
2. Foot placements are *planned*: every heel strike puts the ankle on the path
   ahead of the pelvis, offset sideways by the hip width.  From heel strike to
   heel-off the ankle is held at exactly that point (``y = ankle height``), so
   the stance ankle is bit-for-bit still – the property Peng & Li's
   stance-foot step relies on.  Between heel-off and the next heel strike the
   ankle follows a minimum-jerk swing with a lift.
3. The pelvis height bobs with the gait but is capped so that both legs can
   reach their ankles; the knee is then placed by two-bone inverse kinematics
   in the plane of the facing direction, which keeps thigh and shank lengths
   exact.
4. Spine, neck, head and arms are built from the root down as
   ``child = parent + length * direction``; the directions carry the forward
   lean, the thorax counter-rotation and the arm swing.  Every segment length
   is therefore the class length on every frame.

The generator knows when each foot is planted, so ``contacts`` is exact.

The standing figure (``stand``) is the same generator with no step: both ankles planted for the whole
clip, the pelvis shifting its weight slowly from one foot towards the other, the arms hanging with a
slight bend.  It is the case where a camera that moves all the time and a person who never steps look
alike to a method that reads the camera from the planted feet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..skeleton import (
    ANKLE_HEIGHT_FRACTION,
    CLASS_INDEX,
    CLASSES,
    JOINT_INDEX,
    class_lengths_for_height,
    proportions,
)
from .motion_clip import Motion

#: Names accepted by :func:`builtin_motion` (and ``load_motion("builtin:NAME")``).
BUILTIN_MOTIONS: tuple[str, ...] = ("walk", "run", "stand")

#: Adult class lengths in metres (anthropometric averages for a ~1.75 m man);
#: only their proportions matter, the figure is rescaled to the asked height.
_ADULT_CLASS_LENGTHS_M = {
    "hip": 0.095, "thigh": 0.445, "shank": 0.425, "lower_spine": 0.125, "upper_spine": 0.285,
    "neck": 0.115, "head": 0.215, "clavicle": 0.175, "upper_arm": 0.295, "forearm": 0.265,
}

_UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class _Gait:
    """Parameters of one gait, lengths in units of stature (scaled by height)."""

    duration_s: float
    cadence_steps_per_s: float
    step_length: float          # per stature
    strike_lead: float          # ankle ahead of pelvis at heel strike, per stature
    planted_fraction: float     # heel strike .. heel-off, fraction of the gait cycle
    swing_lift: float           # extra ankle height at mid-swing, per stature
    pelvis_height: float        # nominal pelvis height above the ankle, per leg length
    bob: float                  # pelvis bob per stature: > 0 highest at mid-stance (walk), < 0 lowest (run)
    lean_deg: float
    arm_swing_deg: float
    elbow_flex_deg: float
    elbow_flex_swing_deg: float
    pelvis_yaw_deg: float
    sway: float                 # lateral pelvis sway per stature
    curvature: float            # peak path curvature, 1/m at 1.75 m stature
    turn_wavelength: float      # path length of one left+right turn pair, per stature
    free_swing: bool = False    # the swing foot never bounds the pelvis height (runs)


_GAITS: dict[str, _Gait] = {
    "walk": _Gait(duration_s=10.0, cadence_steps_per_s=1.9, step_length=0.37, strike_lead=0.17,
                  planted_fraction=0.45, swing_lift=0.075, pelvis_height=0.985, bob=0.005,
                  lean_deg=4.0, arm_swing_deg=22.0, elbow_flex_deg=12.0, elbow_flex_swing_deg=14.0,
                  pelvis_yaw_deg=5.0, sway=0.012, curvature=0.6, turn_wavelength=4.0),
    "run": _Gait(duration_s=6.0, cadence_steps_per_s=2.8, step_length=0.75, strike_lead=0.17,
                 planted_fraction=0.24, swing_lift=0.2, pelvis_height=0.93, bob=-0.025,
                 lean_deg=9.0, arm_swing_deg=35.0, elbow_flex_deg=85.0, elbow_flex_swing_deg=10.0,
                 pelvis_yaw_deg=7.0, sway=0.008, curvature=0.3, turn_wavelength=8.0, free_swing=True),
    # standing on the spot: both feet planted the whole clip, the weight shifting slowly from foot to foot
    # (one "step" is one shift), the arms hanging with a slight bend and a small sway
    "stand": _Gait(duration_s=10.0, cadence_steps_per_s=0.3, step_length=0.0, strike_lead=0.0,
                   planted_fraction=1.0, swing_lift=0.0, pelvis_height=0.99, bob=0.0,
                   lean_deg=2.0, arm_swing_deg=5.0, elbow_flex_deg=14.0, elbow_flex_swing_deg=6.0,
                   pelvis_yaw_deg=4.0, sway=0.025, curvature=0.0, turn_wavelength=4.0),
}


def adult_class_lengths(height_m: float = 1.75) -> np.ndarray:
    """The built-in figure's 10 class lengths (metres) for a standing height."""
    raw = np.array([_ADULT_CLASS_LENGTHS_M[name] for name in CLASSES])
    return class_lengths_for_height(proportions(raw), height_m)


def builtin_motion(name: str, height_m: float = 1.75, fps: float | None = None) -> Motion:
    """A built-in procedural :class:`Motion` (see :data:`BUILTIN_MOTIONS`).

    ``fps`` defaults to 30; the clip is sampled analytically, so any rate is
    exact (no resampling).
    """
    if name not in _GAITS:
        raise InputError(f"unknown built-in motion {name!r}; choose one of {', '.join(BUILTIN_MOTIONS)}")
    if not np.isfinite(height_m) or height_m <= 0:
        raise InputError(f"height must be a positive number of metres, got {height_m!r}")
    fps = 30.0 if fps is None else float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"fps must be positive, got {fps!r}")
    gait = _GAITS[name]
    class_lengths = adult_class_lengths(height_m)
    n_frames = max(1, int(round(gait.duration_s * fps)))
    times = np.arange(n_frames) / fps
    joints, contacts = _generate(gait, class_lengths, height_m, times)
    meta = {"source": f"builtin:{name}", "height_m": float(height_m),
            "ankle_height_m": float(ANKLE_HEIGHT_FRACTION * height_m),
            "cadence_steps_per_s": gait.cadence_steps_per_s}
    return Motion(name, fps, joints, class_lengths, contacts, meta)


# --------------------------------------------------------------------------- path


class _Path:
    """A ground path sampled by arc length: position (x, z) and heading."""

    def __init__(self, length_m: float, curvature: float, wavelength_m: float):
        self.ds = 0.005
        s = np.arange(-5.0, length_m + 10.0, self.ds)
        # A short straight start, then alternating left and right turns: the heading swings
        # between 0 and curvature * wavelength / pi (about 75 degrees) and back.
        ramp = np.clip(s / (0.1 * wavelength_m), 0.0, 1.0)
        kappa = curvature * ramp * np.sin(2 * np.pi * s / wavelength_m)
        heading = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * self.ds)])
        heading -= heading[np.searchsorted(s, 0.0)]
        dx, dz = np.sin(heading), np.cos(heading)
        x = np.concatenate([[0.0], np.cumsum(0.5 * (dx[1:] + dx[:-1]) * self.ds)])
        z = np.concatenate([[0.0], np.cumsum(0.5 * (dz[1:] + dz[:-1]) * self.ds)])
        i0 = np.searchsorted(s, 0.0)
        self.s, self.x, self.z, self.heading = s, x - x[i0], z - z[i0], heading

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points (N, 3) on the floor plane (y = 0) and headings (N,) at arc lengths ``s``."""
        s = np.asarray(s, dtype=float)
        x = np.interp(s, self.s, self.x)
        z = np.interp(s, self.s, self.z)
        return np.stack([x, np.zeros_like(x), z], axis=-1), np.interp(s, self.s, self.heading)


def _forward(yaw: np.ndarray) -> np.ndarray:
    return np.stack([np.sin(yaw), np.zeros_like(yaw), np.cos(yaw)], axis=-1)


def _left(yaw: np.ndarray) -> np.ndarray:
    # left = up x forward
    return np.stack([np.cos(yaw), np.zeros_like(yaw), -np.sin(yaw)], axis=-1)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _min_jerk(u: np.ndarray) -> np.ndarray:
    return u ** 3 * (10 - 15 * u + 6 * u ** 2)


# --------------------------------------------------------------------------- generator


def _generate(gait: _Gait, cl: np.ndarray, height: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(times)
    c = {name: cl[CLASS_INDEX[name]] for name in CLASSES}
    leg = c["thigh"] + c["shank"]
    reach = 0.999 * leg
    ankle_h = ANKLE_HEIGHT_FRACTION * height
    scale = height / 1.75
    step = gait.step_length * height
    cycle = 2.0 / gait.cadence_steps_per_s
    speed = step * gait.cadence_steps_per_s
    duration = times[-1] if n else 0.0
    path = _Path(speed * (duration + 2 * cycle) + 5.0, gait.curvature / scale, gait.turn_wavelength * height)

    # --- pelvis ground point, heading and sway
    s_pelvis = speed * times
    ground, heading = path.at(s_pelvis)
    phase = 2 * np.pi * times / cycle          # left heel strikes at phase 0 mod 2 pi
    yaw = heading + np.radians(gait.pelvis_yaw_deg) * np.cos(phase)   # left hip forward at left strike
    sway = gait.sway * height * np.sin(phase)  # over the left foot at left mid-stance, then the right
    pelvis = ground + sway[:, None] * _left(heading)

    # hip offset in the pelvis frame: lateral and a little down
    hip_dir_local = _unit(np.array([1.0, -0.35, 0.0]))   # (left, up, forward) components
    hips = {}
    for side, sign in (("l", 1.0), ("r", -1.0)):
        hips[side] = (sign * hip_dir_local[0] * _left(yaw) + hip_dir_local[1] * _UP) * c["hip"]

    # --- ankles: planned plants, held still while planted, min-jerk swing in between
    ankles, swing_u, contacts = {}, {}, np.zeros((n, 2), dtype=bool)
    for col, (side, offset, sign) in enumerate((("l", 0.0, 1.0), ("r", 0.5, -1.0))):
        k = np.floor(times / cycle - offset)                 # index of the last heel strike
        t_strike = (k + offset) * cycle
        strikes_s = speed * np.stack([t_strike, t_strike + cycle]) + gait.strike_lead * height
        plant_pts = []
        for s_plant in strikes_s:
            pt, hd = path.at(s_plant)
            plant_pts.append(pt + sign * hip_dir_local[0] * c["hip"] * _left(hd))
        plant, next_plant = plant_pts
        u_cycle = (times - t_strike) / cycle
        planted = u_cycle <= gait.planted_fraction
        u = np.clip((u_cycle - gait.planted_fraction) / max(1.0 - gait.planted_fraction, 1e-9), 0.0, 1.0)
        blend = _min_jerk(u)[:, None]
        ankle = plant * (1 - blend) + next_plant * blend
        lift = gait.swing_lift * height * np.sin(np.pi * u ** 0.7) ** 2
        ankle[:, 1] = ankle_h + np.where(planted, 0.0, lift)
        ankle[planted] = plant[planted]
        ankle[planted, 1] = ankle_h
        ankles[side] = ankle
        swing_u[side] = np.where(planted, 0.0, u)
        contacts[:, col] = planted

    # --- pelvis height: nominal bob, capped so every planted ankle is reachable
    bob_phase = 2 * np.pi * (times / (cycle / 2)) - 2 * np.pi * gait.planted_fraction  # 0 at mid-stance
    desired = ankle_h + gait.pelvis_height * leg + gait.bob * height * np.cos(bob_phase) - hips["l"][:, 1]
    # The cap follows the planned ankle path, which is continuous, so the cap is too.  Early in the
    # swing it is relaxed smoothly (the knee folds there; an ankle out of reach is pulled in below),
    # so only the stance and the landing shape the pelvis height.  Smoothing a slightly lowered
    # min() then leaves a curve without kinks that still never overreaches a planted foot.
    allowed = np.full(n, np.inf)
    for side in ("l", "r"):
        hip_xz = pelvis + hips[side]
        d_xz = np.hypot(ankles[side][:, 0] - hip_xz[:, 0], ankles[side][:, 2] - hip_xz[:, 2])
        cap = ankles[side][:, 1] + np.sqrt(np.maximum(reach ** 2 - d_xz ** 2, 0.0)) - hips[side][:, 1]
        u = swing_u[side]
        if gait.free_swing:      # the run: only planted feet bound the pelvis (flight is free)
            relax = np.where(u > 0, 0.2 * height, 0.0)
        else:                    # the walk: the landing foot shapes the double-support dip
            relax = np.where(u < 0.8, np.sin(np.pi * u / 0.8) ** 2, 0.0) * 0.2 * height
        allowed = np.minimum(allowed, cap + relax)
    margin = 0.003 * height
    radius = max(1, int(round(0.05 * n / max(duration, 1e-9))))
    pelvis_y = _smooth(np.minimum(desired, allowed - margin), radius)
    pelvis[:, 1] = np.minimum(pelvis_y, allowed)

    joints = np.zeros((n, 17, 3))
    J = JOINT_INDEX
    joints[:, J["pelvis"]] = pelvis
    fwd_pelvis = _forward(heading)
    for side in ("l", "r"):
        hip = pelvis + hips[side]
        ankle = ankles[side]
        d = ankle - hip
        dist = np.linalg.norm(d, axis=-1)
        # only possible during swing (planted ankles are reachable by the height cap): pull the foot in
        too_far = (dist > reach) & ~contacts[:, 0 if side == "l" else 1]
        ankle = np.where(too_far[:, None], hip + d * (reach / np.maximum(dist, 1e-12))[:, None], ankle)
        joints[:, J[f"{side}_hip"]] = hip
        joints[:, J[f"{side}_knee"]] = _knee(hip, ankle, c["thigh"], c["shank"], fwd_pelvis)
        joints[:, J[f"{side}_ankle"]] = ankle

    # --- trunk and head
    lean = np.radians(gait.lean_deg)
    thorax_yaw = heading - 0.6 * (yaw - heading)
    side_bend = 0.03 * np.sin(phase)
    spine_dir = _unit(np.cos(lean) * _UP + np.sin(lean) * _forward(yaw) + side_bend[:, None] * _left(yaw))
    thorax_dir = _unit(np.cos(lean) * _UP + np.sin(lean) * _forward(thorax_yaw)
                       - side_bend[:, None] * _left(thorax_yaw))
    neck_dir = _unit(np.cos(lean * 1.5) * _UP + np.sin(lean * 1.5) * _forward(thorax_yaw))
    head_dir = _unit(_UP + 0.05 * _forward(heading))
    joints[:, J["spine"]] = pelvis + c["lower_spine"] * spine_dir
    joints[:, J["thorax"]] = joints[:, J["spine"]] + c["upper_spine"] * thorax_dir
    joints[:, J["neck"]] = joints[:, J["thorax"]] + c["neck"] * neck_dir
    joints[:, J["head"]] = joints[:, J["neck"]] + c["head"] * head_dir

    # --- arms: swing opposite to the same-side leg
    fwd_t, left_t = _forward(thorax_yaw), _left(thorax_yaw)
    for side, sign, arm_phase in (("l", 1.0, phase + np.pi), ("r", -1.0, phase)):
        swing = np.radians(gait.arm_swing_deg) * np.cos(arm_phase) + np.radians(3.0)   # + = forward
        flex = np.radians(gait.elbow_flex_deg + gait.elbow_flex_swing_deg * np.cos(arm_phase))
        out = sign * left_t
        shoulder = joints[:, J["thorax"]] + c["clavicle"] * _unit(out + 0.12 * _UP)
        upper = _unit(-np.cos(swing)[:, None] * _UP + np.sin(swing)[:, None] * fwd_t + 0.12 * out)
        fore_angle = swing + flex
        fore = _unit(-np.cos(fore_angle)[:, None] * _UP + np.sin(fore_angle)[:, None] * fwd_t + 0.06 * out)
        joints[:, J[f"{side}_shoulder"]] = shoulder
        joints[:, J[f"{side}_elbow"]] = shoulder + c["upper_arm"] * upper
        joints[:, J[f"{side}_wrist"]] = joints[:, J[f"{side}_elbow"]] + c["forearm"] * fore
    return joints, contacts


def _knee(hip: np.ndarray, ankle: np.ndarray, thigh: float, shank: float, forward: np.ndarray) -> np.ndarray:
    """Two-bone IK: the knee at exact distances from hip and ankle, bending towards ``forward``."""
    d = ankle - hip
    dist = np.linalg.norm(d, axis=-1)
    u = d / dist[:, None]
    w = forward - np.sum(forward * u, axis=-1, keepdims=True) * u
    w = _unit(w)
    cos_a = np.clip((thigh ** 2 + dist ** 2 - shank ** 2) / (2 * thigh * dist), -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a ** 2)
    return hip + thigh * (cos_a[:, None] * u + sin_a[:, None] * w)


def _smooth(values: np.ndarray, radius: int) -> np.ndarray:
    """Gaussian smoothing with edge padding (removes the kinks of the height cap)."""
    if radius < 1 or len(values) < 3:
        return values
    x = np.arange(-3 * radius, 3 * radius + 1)
    kernel = np.exp(-0.5 * (x / radius) ** 2)
    kernel /= kernel.sum()
    padded = np.pad(values, 3 * radius, mode="edge")
    return np.convolve(padded, kernel, mode="valid")
