"""The paper's experiment as a generator: film a rigid figure with a virtual camera.

Peng & Li (2006, section 5) test their method on a 17-joint figure driven by
BVH motion, filmed at 720 x 480 by a camera at a fixed position that pans,
tilts and zooms between still spells, with noise added to the 2D joints.
:func:`synthesize` does exactly that for any :class:`core.synthetic.motion.Motion` and
returns the 2D :class:`core.tracks.Tracks` plus the :class:`core.synthetic.truth.Truth`
an estimate is scored against.

Camera placement (:func:`place_camera`), all from the motion's own geometry:

* aim point: the centre of the horizontal bounding box of all joints over
  the clip, at the middle of their vertical extent;
* viewing direction (horizontal): start from the side view of the pelvis
  path (perpendicular to its principal axis, on the side the figure faces at
  frame 0; a figure whose pelvis stays within ``STATIONARY_PATH_M`` = 0.5 m
  starts from its frame-0 facing direction), then turn it by the first of
  ``VIEW_OFFSETS_DEG`` (+-30, +-45, +-60, +-75 deg) that makes the figure
  largest in the image (10th percentile of its projected height over the
  clip; a later candidate must beat the best by 5 %).  Long walks are thus
  filmed obliquely, nearly along the path, so the figure stays a usable size
  and its depth (Peng & Li's virtual scale) changes; ``view_offset_deg``
  fixes the turn instead;
* height: 0.8 x the figure's standing height, clamped to 1.2-1.6 m;
* distance: the smallest horizontal distance (to 0.2 %) at which
  every joint of every frame, seen from frame 0's orientation with frame 0's
  focal length, falls inside the central ``FIT_FRACTION`` (80 %) of the image
  width and height, so the whole motion is framed with room for camera moves;
* frame-0 orientation: looking at the aim point, no roll (camera x axis level).

Camera schedule: :func:`core.synthetic.synth_camera.make_schedule` (seeded).  When the
schedule is generated here (``schedule=None``), each moving spell is then
adjusted in order, like a camera operator keeping the person in frame: the
signs of its pan/tilt/roll, the direction of its zoom (in or out; the focal
length stays within 1/1.6 .. 1.6 x frame 0's) and the scale of its amplitude
(x1, x0.7, x0.5) are chosen to maximise the visible joints (ankles weigh 3x)
over the spell plus at least ``LOOK_AHEAD_S`` (1 s) after it or until the
next motion, plus half the weight of the rest of the clip with the camera
held still.  The drawn spell wins ties, so most spells keep their drawn
amplitude.  A given ``schedule`` is used unchanged.

Observation model, all deterministic from ``seed`` (separate random streams,
so changing one option does not reshuffle the others):

1. geometry: a joint behind the camera (depth < 5 cm) or projecting outside
   the image is missing;
2. occlusions (``occlusion_s`` > 0): one event per started 6 s of clip, each a
   random limb chain (``l_arm``/``r_arm`` = shoulder, elbow, wrist;
   ``l_leg``/``r_leg`` = hip, knee, ankle) missing for ``occlusion_s`` seconds
   from a random start;
3. drop-outs: exactly ``round(dropout * n)`` of the n observations still
   visible are removed, uniformly at random;
4. noise: Gaussian, ``noise_px`` standard deviation per pixel coordinate.

Visible joints get confidence 1.0 (the noise is not reflected in confidence).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..camera import project_to_pixels, rotvec_deg
from ..errors import InputError
from ..skeleton import JOINT_INDEX, LIMBS, proportions, standing_height
from ..tracks import StaticTracks, Tracks
from .footage_sim.detector import DetectorErrors, apply_detector_errors
from .footage_sim.handheld import HandheldOperator, handheld_camera
from .footage_sim.scene_points import scene_points_world
from .motion import Motion
from .synth_camera import (
    CAMERA_KINDS,
    Spell,
    camera_rotations,
    camera_states,
    check_kinds,
    check_schedule,
    ease,
    make_schedule,
    moving_mask,
)
from .truth import Truth

__all__ = ["CAMERA_KINDS", "Spell", "make_schedule", "synthesize", "place_camera", "stance_truth",
           "CameraPlacement", "LIMBS", "YUP_TO_BLENDER"]

#: Candidate turns (degrees) of the view away from the side view of the path, tried in this order.
VIEW_OFFSETS_DEG = (30.0, -30.0, 45.0, -45.0, 60.0, -60.0, 75.0, -75.0)
STATIONARY_PATH_M = 0.5
FIT_FRACTION = 0.80
MIN_DEPTH_M = 0.05
OCCLUSION_EVERY_S = 6.0
#: Motion world (Y up, BVH) -> Blender world (Z up): (x, y, z) -> (x, -z, y).
YUP_TO_BLENDER = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
_AMPLITUDE_SCALES = (1.0, 0.7, 0.5)
#: Keep-in-frame scoring: look this far past a spell's end, weigh the ankles (stance feet) more.
LOOK_AHEAD_S = 1.0
FOOT_WEIGHT = 3.0
FUTURE_WEIGHT = 0.5     # weight of the rest of the clip (camera assumed held still after the window)
#: The adjusted focal length stays within 1/ZOOM_LIMIT .. ZOOM_LIMIT x frame 0's.
ZOOM_LIMIT = 1.6
_UP = np.array([0.0, 1.0, 0.0])


@dataclass
class CameraPlacement:
    """Where the virtual camera stands and how frame 0 looks (motion world, Y up)."""

    position_world: np.ndarray          # (3,) metres
    rotation_world_from_cam0: np.ndarray  # (3, 3), columns = camera x, y, z axes in the world
    target_world: np.ndarray            # (3,) the aim point
    distance_m: float                   # horizontal distance camera -> aim point
    view_offset_deg: float = 0.0        # turn of the view away from the side view of the path

    def to_cam0(self, points_world: np.ndarray) -> np.ndarray:
        """World points (..., 3) to frame-0 camera coordinates."""
        return (np.asarray(points_world, dtype=float) - self.position_world) @ self.rotation_world_from_cam0

    def world_from_cam0_blender(self) -> np.ndarray:
        """4x4: frame-0 camera coordinates -> Blender world (Z up, floor z = 0)."""
        m = np.eye(4)
        m[:3, :3] = YUP_TO_BLENDER @ self.rotation_world_from_cam0
        m[:3, 3] = YUP_TO_BLENDER @ self.position_world
        return m


#: Takes a handheld operator may film to keep the person in the picture.
HANDHELD_TAKES = 8


def _horizontal(v: np.ndarray) -> np.ndarray:
    return np.array([v[0], 0.0, v[2]])


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-12 else v


def _look_rotation(position: np.ndarray, target: np.ndarray) -> np.ndarray:
    z = _unit(target - position)
    x = _unit(np.cross(z, _UP))
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def _sample_frames(n: int, limit: int = 600) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, limit)).round().astype(int))


def _view_base(joints: np.ndarray) -> np.ndarray:
    """Horizontal unit vector from the scene centre to the camera before the offset turn."""
    pelvis = joints[:, JOINT_INDEX["pelvis"]]
    facing = _unit(np.cross(_horizontal(joints[0, JOINT_INDEX["l_hip"]] - joints[0, JOINT_INDEX["r_hip"]]), _UP))
    if float(np.linalg.norm(facing)) < 0.5:
        facing = np.array([0.0, 0.0, 1.0])
    extent = float(np.ptp(pelvis[:, [0, 2]], axis=0).max())
    if extent < STATIONARY_PATH_M:
        return facing
    path = pelvis[:, [0, 2]] - pelvis[:, [0, 2]].mean(axis=0)
    _, _, vt = np.linalg.svd(path, full_matrices=False)
    side = _unit(np.cross(_UP, np.array([vt[0, 0], 0.0, vt[0, 1]])))
    return side if float(side @ facing) >= 0 else -side


def _fit(pts: np.ndarray, target: np.ndarray, view: np.ndarray, height: float, image_size, focal_mm: float,
         fit_fraction: float) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Smallest distance (to 0.2 %) at which ``pts`` fit the central box; None if none up to 2 km."""
    w, h = float(image_size[0]), float(image_size[1])
    half = np.array([w, h]) * fit_fraction / 2.0
    centre = np.array([w, h]) / 2.0

    def pose(d: float):
        pos = np.array([target[0] + d * view[0], height, target[2] + d * view[2]])
        return pos, _look_rotation(pos, target)

    def fits(d: float) -> bool:
        pos, rot = pose(d)
        cam = (pts - pos) @ rot
        if not (cam[:, 2] > MIN_DEPTH_M).all():
            return False
        return bool((np.abs(project_to_pixels(cam, focal_mm, (w, h)) - centre) <= half).all())

    lo, hi = 0.0, 1.0
    while not fits(hi):            # coarse scan, then bisection between the last miss and the first fit
        lo, hi = hi, hi * 1.25
        if hi > 2000.0:
            return None
    while hi - lo > 0.002 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    pos, rot = pose(hi)
    return pos, rot, hi


def place_camera(joints: np.ndarray, class_lengths: np.ndarray, image_size, focal_mm: float, *,
                 view_offset_deg: float | None = None, fit_fraction: float = FIT_FRACTION) -> CameraPlacement:
    """Fixed camera framing the whole motion at frame 0 (rules in the module docstring).

    ``view_offset_deg`` turns the view away from the side view of the path;
    None picks it from :data:`VIEW_OFFSETS_DEG` to make the figure as large as
    possible (best 10th percentile of its projected height over the clip).
    """
    joints = np.asarray(joints, dtype=float)
    frames = _sample_frames(joints.shape[0])
    pts = joints[frames].reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = (lo + hi) / 2.0
    base = _view_base(joints)
    height = float(np.clip(0.8 * float(standing_height(class_lengths)), 1.2, 1.6))
    offsets = VIEW_OFFSETS_DEG if view_offset_deg is None else (float(view_offset_deg),)
    best, best_size = None, -1.0
    for off in offsets:
        a = math.radians(off)
        view = np.array([base[0] * math.cos(a) + base[2] * math.sin(a), 0.0,
                         -base[0] * math.sin(a) + base[2] * math.cos(a)])
        found = _fit(pts, target, view, height, image_size, focal_mm, fit_fraction)
        if found is None:
            continue
        pos, rot, d = found
        v = project_to_pixels((pts - pos) @ rot, focal_mm, image_size)[:, 1].reshape(len(frames), -1)
        size = float(np.percentile(v.max(axis=1) - v.min(axis=1), 10))
        if size > best_size * 1.05:      # a wider offset must win clearly
            best, best_size = CameraPlacement(pos, rot, target, d, off), size
    if best is None:
        raise InputError("cannot frame the motion: it is too large or degenerate for the virtual camera")
    return best


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each frame, start and end (inclusive) of the run of True containing it (-1 where False)."""
    n = len(mask)
    start = np.full(n, -1)
    end = np.full(n, -1)
    i = 0
    while i < n:
        if mask[i]:
            j = i
            while j + 1 < n and mask[j + 1]:
                j += 1
            start[i:j + 1] = i
            end[i:j + 1] = j
            i = j + 1
        else:
            i += 1
    return start, end


def stance_truth(contacts: np.ndarray) -> tuple[list, np.ndarray]:
    """Stance foot per frame from foot contacts (F, 2) = (left, right) planted.

    * exactly one foot planted: that foot; ``stance_clear`` is True;
    * both planted (double support): the foot planted EARLIER (the old stance
      foot keeps the stance until it lifts off, so the stance swaps at toe-off,
      and a stance spell is a stretch where that foot is truly static); if both
      touched down on the same frame, the one that stays planted longer; then
      "l"; ``stance_clear`` is False;
    * neither (flight): None, ``stance_clear`` False.
    """
    c = np.asarray(contacts, dtype=bool)
    ls, le = _runs(c[:, 0])
    rs, re = _runs(c[:, 1])
    stance: list = []
    for i in range(len(c)):
        left, right = bool(c[i, 0]), bool(c[i, 1])
        if left and right:
            if ls[i] != rs[i]:
                stance.append("l" if ls[i] < rs[i] else "r")
            else:
                stance.append("r" if re[i] > le[i] else "l")
        elif left:
            stance.append("l")
        elif right:
            stance.append("r")
        else:
            stance.append(None)
    return stance, c.sum(axis=1) == 1


def _visible(cam: np.ndarray, focal: np.ndarray, image_size) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (n, 17, 2) and visibility (n, 17) of points in each frame's camera coordinates."""
    z = cam[..., 2]
    in_front = z > MIN_DEPTH_M
    safe = np.where(in_front[..., None], cam, np.array([0.0, 0.0, 1.0]))
    uv = project_to_pixels(safe, focal[:, None], image_size)
    w, h = image_size
    inside = (uv[..., 0] >= 0) & (uv[..., 0] <= w) & (uv[..., 1] >= 0) & (uv[..., 1] <= h)
    return uv, in_front & inside


def _scaled(spell: Spell, signs: tuple[float, float, float], scale: float, zoom_flip: bool) -> dict:
    p = dict(spell.params)
    for key, s in zip(("pan_deg", "tilt_deg", "roll_deg"), signs, strict=True):
        if key in p:
            p[key] = s * scale * p[key]
    if "zoom" in p:
        p["zoom"] = float(p["zoom"]) ** (-scale if zoom_flip else scale)
    return p


def _keep_in_frame(spells: list[Spell], cam0: np.ndarray, focal_mm: float, image_size, fps: float) -> list[Spell]:
    """Adjust each motion spell, in order, to keep the figure in frame (rules in the module docstring)."""
    spells = [Spell(s.start, s.end, s.kind, dict(s.params)) for s in spells]
    n = cam0.shape[0]
    weight = np.ones(cam0.shape[1])
    weight[[JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]] = FOOT_WEIGHT
    weight /= weight.sum()
    hold = int(round(fps * LOOK_AHEAD_S))
    motion_idx = [k for k, s in enumerate(spells) if s.moving and s.params]
    log_ratio = 0.0
    for order, k in enumerate(motion_idx):
        spell = spells[k]
        nxt = spells[motion_idx[order + 1]].start if order + 1 < len(motion_idx) else n
        stop = min(n, max(nxt, spell.end + 1 + hold))
        axes = [key for key in ("pan_deg", "tilt_deg", "roll_deg") if key in spell.params]
        sign_sets = [(1.0, 1.0, 1.0)]
        for key in axes:
            i = ("pan_deg", "tilt_deg", "roll_deg").index(key)
            sign_sets += [tuple(-v if j == i else v for j, v in enumerate(s)) for s in sign_sets]
        flips = (False, True) if "zoom" in spell.params else (False,)
        best, best_score = None, -1.0
        # score on at most ~120 frames of the window, and as much of the rest of the clip, the camera held still
        near = np.unique(np.linspace(spell.start, stop - 1, min(120, stop - spell.start)).round().astype(int))
        far = np.unique(np.linspace(stop, n - 1, min(120, n - stop)).round().astype(int)) if stop < n else near[:0]
        frames = np.concatenate([near, far])
        for scale in _AMPLITUDE_SCALES:
            for flip in flips:
                params0 = _scaled(spell, (1.0, 1.0, 1.0), scale, flip)
                if abs(log_ratio + math.log(params0.get("zoom", 1.0))) > math.log(ZOOM_LIMIT) + 1e-9:
                    continue
                for signs in sign_sets:
                    trial = list(spells)
                    trial[k] = Spell(spell.start, spell.end, spell.kind, _scaled(spell, signs, scale, flip))
                    angles, focal = _window_states(trial, k, n, focal_mm)
                    rot = camera_rotations(angles[frames - spell.start])
                    cam = np.einsum("fij,fkj->fki", rot, cam0[frames])
                    _, vis = _visible(cam, focal[frames - spell.start], image_size)
                    seen = vis @ weight
                    score = float(seen[:len(near)].mean())
                    if len(far):
                        score += FUTURE_WEIGHT * float(seen[len(near):].mean())
                    if score > best_score + 1e-9:
                        best, best_score = trial[k], score
        spells[k] = best if best is not None else Spell(spell.start, spell.end, spell.kind, dict(spell.params))
        log_ratio += math.log(spells[k].params.get("zoom", 1.0))
    return spells


def _window_states(spells: list[Spell], k: int, stop: int, focal_mm: float):
    """Camera states of frames spells[k].start .. stop-1, with the frames after spells[k] held still."""
    keys = ("pan_deg", "tilt_deg", "roll_deg")
    before = np.array([sum(s.params.get(key, 0.0) for s in spells[:k]) for key in keys])
    log_f = math.log(focal_mm) + sum(math.log(s.params.get("zoom", 1.0)) for s in spells[:k])
    spell = spells[k]
    p = np.ones(stop - spell.start)
    p[:spell.n_frames] = ease(spell.n_frames)
    delta = np.array([spell.params.get(key, 0.0) for key in keys])
    angles = before + p[:, None] * delta
    focal = np.exp(log_f + p * math.log(spell.params.get("zoom", 1.0)))
    return angles, focal


def _check_number(name: str, value, *, lo: float, hi: float = math.inf, lo_open: bool = False,
                  hi_open: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        v = float(value)
        ok = (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        lo_s = "(" if lo_open else "["
        hi_s = ")" if hi_open else "]"
        raise InputError(f"{name} must be a number in {lo_s}{lo}, {hi}{hi_s}, got {value!r}")
    return float(value)


def synthesize(motion: Motion, *, kinds=("pan", "tilt", "zoom"), schedule: list[Spell] | None = None,
               focal_mm: float = 50.0, image_size=(720, 480), noise_px: float = 1.0, dropout: float = 0.0,
               occlusion_s: float = 0.0, seed: int = 0, continuous: bool = False,
               view_offset_deg: float | None = None, operator: HandheldOperator | None = None,
               detector: DetectorErrors | None = None, static_points: int = 0) -> tuple[Tracks, Truth]:
    """Film ``motion`` with the virtual camera; return (tracks, truth).  Rules: module docstring.

    ``operator``: a handheld operator (:mod:`core.synthetic.footage_sim.handheld`) instead of the paper's
    tripod schedule; ``detector``: a real detector's errors (:mod:`core.synthetic.footage_sim.detector`)
    instead of Gaussian noise alone; ``static_points``: that many static scene points tracked too
    (:mod:`core.synthetic.footage_sim.scene_points`; Gaussian noise of ``noise_px``).
    """
    kinds = check_kinds(kinds)
    focal_mm = _check_number("focal length (mm)", focal_mm, lo=0.0, lo_open=True)
    noise_px = _check_number("noise (px)", noise_px, lo=0.0)
    dropout = _check_number("drop-out fraction", dropout, lo=0.0, hi=1.0, hi_open=True)
    occlusion_s = _check_number("occlusion duration (s)", occlusion_s, lo=0.0)
    try:
        w, h = (float(v) for v in image_size)
    except (TypeError, ValueError):
        raise InputError(f"image size must be (width, height), got {image_size!r}") from None
    if not (math.isfinite(w) and math.isfinite(h) and w >= 16 and h >= 16):
        raise InputError(f"image size must be at least 16 x 16 pixels, got {image_size!r}")
    size = (w, h)
    joints = np.asarray(motion.joints, dtype=float)
    n = joints.shape[0] if joints.ndim == 3 else 0
    if joints.ndim != 3 or joints.shape[1:] != (17, 3) or n < 2:
        raise InputError(f"{motion.name}: motion needs joints shaped (frames >= 2, 17, 3), got {joints.shape}")
    if not np.isfinite(joints).all():
        raise InputError(f"{motion.name}: motion has non-finite joint positions")
    fps = float(motion.fps)
    if not (math.isfinite(fps) and fps > 0):
        raise InputError(f"{motion.name}: motion fps must be positive, got {motion.fps!r}")
    contacts = np.asarray(motion.contacts, dtype=bool)
    if contacts.shape != (n, 2):
        raise InputError(f"{motion.name}: contacts must be shaped ({n}, 2), got {contacts.shape}")

    placement = place_camera(joints, motion.class_lengths, size, focal_mm, view_offset_deg=view_offset_deg)
    cam0 = placement.to_cam0(joints)
    if operator is not None:
        if schedule is not None:
            raise InputError("give a camera schedule or a handheld operator, not both")
        pelvis = cam0[:, JOINT_INDEX["pelvis"]]

        def figure_offset(f: int) -> tuple[float, float]:
            x, y, z = pelvis[f]
            return math.degrees(math.atan2(x, z)), math.degrees(math.atan2(y, z))

        # an operator keeps the person in the picture: of a few takes, the first that shows 95 % of the
        # joints, else the one that shows most
        best = None
        for take in range(HANDHELD_TAKES):
            angles, focal, spells = handheld_camera(n, fps, focal_mm, figure_offset, seed * HANDHELD_TAKES + take,
                                                    operator)
            cam = np.einsum("fij,fkj->fki", camera_rotations(angles), cam0)
            shown = float(_visible(cam, focal, size)[1].mean())
            if best is None or shown > best[0]:
                best = (shown, angles, focal, spells)
            if shown >= 0.95:
                break
        angles, focal, spells = best[1:]
    else:
        if schedule is None:
            spells = make_schedule(n, fps, kinds, seed, continuous=continuous)
            spells = _keep_in_frame(spells, cam0, focal_mm, size, fps)
        else:
            spells = check_schedule([Spell(s.start, s.end, s.kind, dict(s.params)) for s in schedule], n)
        angles, focal = camera_states(spells, n, focal_mm)
    rot = camera_rotations(angles)
    if not np.allclose(rot[0], np.eye(3), atol=1e-12):
        # a handheld take starts mid-shake: frame 0's camera defines the axes (core.camera), so turn the
        # placement, the joints and every rotation to make R_0 the identity
        r0 = rot[0].copy()
        rot = rot @ r0.T
        cam0 = cam0 @ r0.T
        placement = dataclasses.replace(placement, rotation_world_from_cam0=placement.rotation_world_from_cam0 @ r0.T)
    centre = np.zeros((n, 3))
    if operator is not None and operator.walk_m_s:
        centre[:, 0] = operator.walk_m_s * np.arange(n) / fps    # a walking operator: the camera translates
    cam = np.einsum("fij,fkj->fki", rot, cam0 - centre[:, None])
    uv, visible = _visible(cam, focal, size)

    occlusions: list[dict] = []
    if occlusion_s > 0:
        rng = np.random.default_rng([int(seed), 3])
        length = min(n, max(1, int(round(occlusion_s * fps))))
        events = max(1, int(math.ceil(n / (OCCLUSION_EVERY_S * fps))))
        names = list(LIMBS)
        for _ in range(events):
            limb = names[int(rng.integers(len(names)))]
            start = int(rng.integers(0, n - length + 1))
            visible[start:start + length, list(LIMBS[limb])] = False
            occlusions.append({"start": start, "end": start + length - 1, "limb": limb})
    if dropout > 0:
        rng = np.random.default_rng([int(seed), 2])
        idx = np.flatnonzero(visible)
        k = int(round(dropout * idx.size))
        if k:
            visible.flat[rng.choice(idx, size=k, replace=False)] = False
    detector_log = None
    if detector is not None and detector.any:
        xy, conf, detector_log = apply_detector_errors(uv, visible, noise_px, fps, size, detector, seed)
    else:
        noise = np.random.default_rng([int(seed), 1]).normal(0.0, 1.0, uv.shape) * noise_px
        xy = np.where(visible[..., None], uv + noise, np.nan)
        conf = visible.astype(float)

    static = None
    if static_points:
        if not isinstance(static_points, int) or static_points < 0:
            raise InputError(f"static points must be a whole number >= 0, got {static_points!r}")
        pts0 = placement.to_cam0(scene_points_world(joints, placement.position_world, static_points, seed))
        suv, sseen = _visible(np.einsum("fij,fkj->fki", rot, pts0[None] - centre[:, None]), focal, size)
        snoise = np.random.default_rng([int(seed), 6]).normal(0.0, 1.0, suv.shape) * noise_px
        static = StaticTracks([f"bg_{k}" for k in range(static_points)],
                              np.where(sseen[..., None], suv + snoise, np.nan), sseen.astype(float))

    stance, clear = stance_truth(contacts)
    pelvis_z = cam0[:, JOINT_INDEX["pelvis"], 2]
    scale = pelvis_z[0] / pelvis_z
    class_lengths = np.asarray(motion.class_lengths, dtype=float)
    settings = {"kinds": list(kinds), "continuous": bool(continuous), "focal_mm": focal_mm,
                "noise_px": noise_px, "dropout": dropout, "occlusion_s": occlusion_s, "seed": int(seed),
                "view_offset_deg": float(placement.view_offset_deg), "camera_distance_m": float(placement.distance_m),
                "schedule_given": schedule is not None}
    if operator is not None:
        settings["operator"] = "handheld"
        settings["shake_deg"] = float(operator.shake_deg)
        settings["walk_m_s"] = float(operator.walk_m_s)
    if static is not None:
        settings["static_points_cam0"] = np.round(pts0, 4).tolist()
    if detector_log is not None:
        settings["detector"] = detector.as_dict()
        settings["detector_log"] = detector_log
    truth = Truth(
        source=motion.name, fps=fps, image_size=size,
        proportions=proportions(class_lengths), class_lengths_m=class_lengths.copy(),
        height_m=float(standing_height(class_lengths)),
        camera_position_world=placement.position_world.copy(),
        rotation_world_from_cam0=placement.rotation_world_from_cam0.copy(),
        world_from_cam0=placement.world_from_cam0_blender(), spells=spells, stance=stance, stance_clear=clear,
        camera_moving=moving_mask(spells, n), rotvec_deg=rotvec_deg(rot), focal_mm=focal, scale=scale,
        joints_3d=cam0, occlusions=occlusions, generator=settings)
    # Tracks carry no truth (an estimator must not be able to peek): only that they are synthetic.
    tracks = Tracks(xy, conf, fps, size, source=f"synth:{motion.name}", meta={"synthetic": True}, static=static)
    return tracks, truth
