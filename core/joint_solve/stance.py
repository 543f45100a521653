"""Which foot is planted: a 2D guess to start the solve, a 3D decision after it.

2D (before any 3D exists): under a smoothly moving camera a planted foot's
image moves only with the camera, so its frame-to-frame image displacement
changes slowly; the swing foot's does not.  A two-state chain (left / right
planted for the frame pair i, i+1) costs the change of the chosen foot's
displacement between neighbouring pairs plus a penalty per swap; Viterbi
(:func:`.signs_dp.viterbi`) finds the best labelling in linear time.

3D (after a solve): the planted foot is the one that does not move in the
static frame-0 axes.  Three states per frame (left, right, neither – e.g. a
running flight phase), unary cost from the ankle's speed, swap penalty,
Viterbi again.

Tried and not used (stance accuracy on the frames with exactly one foot planted, 15 clips, 1 px): the
foot that moves less in the image, smoothed by a two-state Viterbi, averages 83-89 % against the
paper's 89 % (better on jogging 88-90 against 69 and the dance 92-95 against 67, worse on the walks
77-83 against 93-100, and 60 against 84 on ``131_01``); the same after undoing the paper's camera
averages 88-90 % (jogging back to 70: that camera is wrong there).  The paper's stance is kept.

What bounds it is the camera: after undoing the *true* camera the same rule reaches 96.2 % on
average (jogging 100, the walks 98-100; 131_01 86, the dance 75-94 depending on the swap penalty).
Taking for each foot the smaller of its raw and its camera-undone speed (either hypothesis may hold
the foot still) averages 90.6-91.3 % over a grid of settings, but single clips swing with the
settings (the dance 48-95 %), so it is not used either.

The stance the joint method *reports* comes from its solved motion in world axes
(:func:`stance_from_world`): the planted foot is the slow one **and the low one**.  Speed alone in 3D
averages 83 % on the 15 clips at 1 px (jogging 18 %: a wrong camera track makes every foot move), height
alone 85 %, the paper's stance 89 %; the two together 93 % (see :data:`WORLD_HEIGHT_SIGMA`).
Adding the ankle's *image* speed (at the pelvis' depth, in body heights per second) as a third term (1 px,
the shipped solve): with its sigma at 0.15 / 0.3 / 0.6, 93.3 / 92.9 / 92.8 % against 92.8 (jogging 84 -> 94 at
0.15, but ``walk_old`` 96 -> 91); the same after undoing the solved camera, 92.6 / 92.8 / 92.7 %; the image
speed alone in the paper's still spells, 93.0 %.  Not used.
Measured again on 15 clips x seeds 0-2 at 1 px, on the shipped solve (92.4 % as reported): the decision
shifted by -4..+4 frames peaks at no shift (91.4 / 92.4 / 91.1 % at -1 / 0 / +1), so there is no lag to
remove; of the 498 wrong one-foot frames, 321 lie within 2 frames of a truth swap or a double support
(58 of side-skip's 59, whose contacts last 4-6 frames) and 113 of the other 177 are the dance's.  The
paper's stance as a fourth term (0.5-8 per frame that disagrees) 92.2-92.9 %; speeds over 5 frames
instead of 3, the vertical speed weighted 3 times, with the speed sigma 0.1 / 0.15 / 0.25 and the swap
penalty 3 / 6: 91.8-92.5 %.  A plateau: the rule is bounded by the solved motion, not by its settings.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..skeleton import FEET, JOINT_INDEX
from .signs_dp import viterbi

NONE = -1                     # stance codes: 0 left, 1 right, NONE neither

#: :func:`stance_from_world`'s sigmas: ankle speed in body heights per second, ankle height above the
#: lower ankle in body heights (0.01 = 1.75 cm for a 1.75 m person), and the cost of swapping feet.
#: Their ratio is what matters.  Measured on the joint method's solved motion, 15 clips (14 shared + the
#: built-in walk, 900 frames max, pan/tilt/zoom), stance accuracy on the frames with exactly one foot
#: planted, mean over clips at 0 / 1 / 2 px: the paper's stance (reported before) 89.5 / 89.4 / 88.0 %;
#: these sigmas 92.6 / 93.1 / 91.5 %.  The grid around them (speed 0.08-0.3, height 0.01-0.04, swap 2-12,
#: 1 px) gives 89.5-93.1 %, better than the paper's wherever the height sigma is at most a tenth of the
#: speed sigma; the height measured from the 5th percentile of all ankle heights instead of the lower
#: ankle, 88.3-92.8 %.  Per clip at 1 px, paper -> this: jogging 69 -> 78 %, side-skip 68 -> 78, the dance
#: 67 -> 86, ``131_01`` 84 -> 95, ``walk_old`` 93 -> 97; neutral 100 -> 99, the rest within 1 point.
#: (All measured on the solve that used the paper's stance throughout.  Since the sign rounds hold this
#: stance, :data:`.pipeline.STANCE_FROM_FIRST_SOLVE`, the stance reported is 91.8 / 92.8 / 90.9 %, jogging
#: 84 %, side-skip 74 %.)
#: A third state, "neither foot" (flight), at a fixed cost of 4-100, with the height above the floor or above
#: the other ankle (1 px): it finds 3-30 % of the frames where no single foot is planted and costs 1-13 % of
#: the one-foot frames (accuracy there 80-92 %; jogging 9-69 %), so the reported stance has two states.
WORLD_SPEED_SIGMA = 0.15
WORLD_HEIGHT_SIGMA = 0.01
WORLD_SWAP_PENALTY = 6.0
#: With a camera from background points, :func:`stance_from_world` adds each ankle's *image* speed with that
#: camera undone (:func:`undone_ankle_speeds`, body heights per second at the pelvis' depth) at this sigma.
#: A planted foot then stands still in the picture to the tracking noise, whatever the depth's noise.
#: Chosen on the tune half with 8-16 background tracks (5 clips; 15 handheld target cases at 30 fps with
#: a detector's errors, 15 broad ones; stance on the one-foot frames, mean / median case), without the
#: term -> sigma 0.1 / 0.2 / 0.4: target 91.9 / 93.2 -> 93.6 / 94.4, 93.0 / 94.4, 92.7 / 93.6 %; broad
#: 92.8 / 93.1 -> 92.7 / 94.7, 92.5 / 94.3, 92.8 / 93.1 % (131_01's second target draw 78 -> 94.5 at 0.1);
#: proportions and 3D unchanged (0.356 -> 0.357 pp, 99.9 -> 99.6 mm, all 30).  From the person alone the
#: undone camera is the solve's own and the term did not help (above), so it is left out there.
IMAGE_SPEED_SIGMA = 0.1


def stance_codes(labels) -> np.ndarray:
    """(F,) stance codes from per-frame labels "l" / "r" / None (an Estimate's or a Truth's stance)."""
    return np.array([{"l": 0, "r": 1}.get(s, NONE) for s in labels], dtype=int)


def stance_from_2d(xy_filled: np.ndarray, swap_penalty: float = 4.0, sigma_px: float = 2.0) -> np.ndarray:
    """(F,) stance guess 0/1 from filled pixel tracks (F, 17, 2)."""
    n = xy_filled.shape[0]
    if n < 3:
        return np.zeros(n, dtype=int)
    feet = np.stack([xy_filled[:, FEET["l"]], xy_filled[:, FEET["r"]]], axis=0)  # (2, F, 2)
    disp = feet[:, 1:] - feet[:, :-1]                                            # (2, F-1, 2)
    unary = 0.02 * np.sum(disp ** 2, axis=-1).T / sigma_px ** 2                  # (F-1, 2)
    change = disp[None, :, 1:] - disp[:, None, :-1]                              # (from, to, F-2, 2)
    pairwise = np.sum(change ** 2, axis=-1) / sigma_px ** 2
    pairwise = pairwise + swap_penalty * (1 - np.eye(2))[:, :, None]
    path = viterbi(unary, np.transpose(pairwise, (2, 0, 1)))
    return np.concatenate([path, path[-1:]])


def _central_speed(path: np.ndarray, fps: float) -> np.ndarray:
    """(F,) speed along a (F, d) path per second, central differences, the ends copied in (F >= 3)."""
    v = np.empty(path.shape[0])
    v[1:-1] = np.linalg.norm(path[2:] - path[:-2], axis=-1) * fps / 2.0
    v[0], v[-1] = v[1], v[-2]
    return v


def _ankle_speeds(joints: np.ndarray, fps: float, height_m: float) -> np.ndarray:
    """(F, 2) left and right ankle speeds in body heights per second (central differences), F >= 3."""
    return np.stack([_central_speed(joints[:, FEET[side]], fps) for side in ("l", "r")], axis=1) / height_m


def undone_ankle_speeds(film: np.ndarray, joints: np.ndarray, rotvec: np.ndarray, focal_mm: np.ndarray,
                        fps: float, height_m: float) -> np.ndarray:
    """(F, 2) left and right ankle image speeds with the camera undone, in body heights per second.

    ``film``: the observed film positions (F, 17, 2) mm, NaN where unseen; ``joints``: the solved joints in
    frame-0 camera axes (F, 17, 3); ``rotvec`` (F, 3) radians and ``focal_mm`` (F,): the solved camera.
    Each observed ankle's ray is turned back into frame 0's axes and projected at frame 0's focal length;
    its speed (central differences) is scaled to metres at the pelvis' depth.  NaN where an ankle is
    unseen in a neighbouring frame.
    """
    n = film.shape[0]
    out = np.full((n, 2), np.nan)
    if n < 3:
        return out
    R = Rotation.from_rotvec(rotvec).as_matrix()
    f = np.asarray(focal_mm, dtype=float)
    depth = joints[:, JOINT_INDEX["pelvis"], 2].copy()
    depth[0], depth[-1] = depth[1], depth[-2]                  # the ends' speeds are their neighbours'
    for k, side in enumerate(("l", "r")):
        a = film[:, FEET[side]]
        ray = np.concatenate([a, f[:, None]], axis=1)
        back = np.einsum("nji,nj->ni", R, ray)                 # R^T ray: frame 0's axes
        und = f[0] * back[:, :2] / back[:, 2:3]
        out[:, k] = _central_speed(und, fps) * depth / f[0] / height_m
    return out


def stance_from_world(joints_world: np.ndarray, fps: float, height_m: float,
                      image_speed: np.ndarray | None = None) -> np.ndarray:
    """(F,) stance 0 left / 1 right from joints in world axes (F, 17, 3), Z up: the slow, low foot.

    Each frame costs the chosen ankle's speed (:data:`WORLD_SPEED_SIGMA`) and its height above the
    other ankle, if higher (:data:`WORLD_HEIGHT_SIGMA`), plus :data:`WORLD_SWAP_PENALTY` per swap;
    Viterbi finds the cheapest labelling.  The height is taken against the other ankle, not the floor,
    so a floor put a little off does not matter.  ``image_speed`` (F, 2), from
    :func:`undone_ankle_speeds` when the camera is known from the background, adds the ankle's speed in
    the picture (:data:`IMAGE_SPEED_SIGMA`; NaN adds nothing).
    """
    n = joints_world.shape[0]
    if n < 3:
        return np.zeros(n, dtype=int)
    speed = _ankle_speeds(joints_world, fps, height_m)
    z = joints_world[:, [FEET["l"], FEET["r"]], 2] / height_m
    above = z - z.min(axis=1, keepdims=True)
    unary = (speed / WORLD_SPEED_SIGMA) ** 2 + (above / WORLD_HEIGHT_SIGMA) ** 2
    if image_speed is not None:
        unary = unary + np.nan_to_num((np.asarray(image_speed) / IMAGE_SPEED_SIGMA) ** 2, nan=0.0)
    pair = WORLD_SWAP_PENALTY * (1 - np.eye(2))
    return viterbi(unary, np.broadcast_to(pair, (n - 1, 2, 2)))


def stance_from_3d(joints: np.ndarray, fps: float, height_m: float, swap_penalty: float = 6.0) -> np.ndarray:
    """(F,) stance 0 left / 1 right / -1 neither, from joints in static axes (F, 17, 3)."""
    n = joints.shape[0]
    if n < 3:
        return np.full(n, NONE)
    speed = _ankle_speeds(joints, fps, height_m)
    # state 0/1: that foot planted (cost grows with its speed); state 2: neither
    sig = 0.08
    unary = np.concatenate([(speed / sig) ** 2, np.full((n, 1), 9.0)], axis=1)
    # a foot that moves much slower than the other is a strong hint even when both move
    pair = np.full((3, 3), swap_penalty) * (1 - np.eye(3))
    path = viterbi(unary, np.broadcast_to(pair, (n - 1, 3, 3)))
    return np.where(path == 2, NONE, path)


def _figure_vector(xy: np.ndarray, tail: tuple[int, ...], head: tuple[int, ...]) -> np.ndarray:
    """(F, 2) the vector from the mean of joints ``tail`` to the mean of joints ``head`` in the picture, in
    units of the figure's spread (root-mean-square distance of its joints from their centre); NaN where
    those joints are not seen.  Dividing by the spread makes it blind to a zoom."""
    xy = np.asarray(xy, dtype=float)
    seen = np.isfinite(xy).all(axis=-1)
    count = np.maximum(seen.sum(axis=1), 1)[:, None]
    filled = np.where(seen[..., None], xy, 0.0)
    centre = filled.sum(axis=1) / count
    square = np.where(seen, np.sum((filled - centre[:, None]) ** 2, axis=-1), 0.0)
    spread = np.sqrt(square.sum(axis=1) / count[:, 0])
    spread[~seen.any(axis=1) | (spread <= 0)] = np.nan
    return (xy[:, list(head)].mean(axis=1) - xy[:, list(tail)].mean(axis=1)) / spread[:, None]


def _relative_speed(xy: np.ndarray, fps: float, tail: tuple[int, ...], head: tuple[int, ...],
                    window_s: float, quantile: float = 0.5) -> float:
    """The ``quantile`` over frames (the median by default) of the speed of :func:`_figure_vector` (the
    figure's spread per second), after a running median over ``window_s``; NaN with too few frames where
    those joints are seen."""
    from scipy.ndimage import median_filter

    vector = _figure_vector(xy, tail, head)
    ok = np.isfinite(vector).all(axis=1)
    if ok.sum() < 3 or not fps or fps <= 0:
        return float("nan")
    k = max(3, int(round(window_s * fps)) | 1)
    smooth = median_filter(vector[ok], size=(k, 1), mode="nearest")
    return float(np.quantile(np.linalg.norm(np.diff(smooth, axis=0), axis=-1), quantile) * fps)


def feet_apart_speed(xy: np.ndarray, fps: float, window_s: float = 0.2, quantile: float = 0.5) -> float:
    """How fast the two ankles move against each other in the picture (:func:`_relative_speed`: the figure's
    spread per second, the median over frames or another ``quantile``).

    Why: turning, zooming or carrying the camera moves both ankles' pictures together, while a step moves
    one against the other.  A person standing on the spot reads near zero whatever the camera does (0.1-0.2
    on the built-in standing figure, with a detector's errors), a walk or run 1-8."""
    return _relative_speed(xy, fps, (FEET["r"],), (FEET["l"],), window_s, quantile)


def hips_over_feet_speed(xy: np.ndarray, fps: float, window_s: float = 0.2) -> float:
    """How fast the hips move against the feet in the picture (the mid-hip point against the mid-ankle
    point, :func:`_relative_speed`).

    Why: a jump with the feet together, a crouch or a lunge moves the hips over the feet without moving
    the feet apart; a person who only stands and shifts the weight barely does (0.05-0.14 on the built-in
    standing figure, 0.4 or more for the walks and runs)."""
    return _relative_speed(xy, fps, (FEET["l"], FEET["r"]), (JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]), window_s)


#: The strides :func:`stride_period` looks for (seconds): a running stride (150-190 steps a minute) is 0.6-0.8 s,
#: a walking one (90-125 steps a minute) 1.0-1.3 s; slower than 2 s is not a gait.
STRIDE_RANGE_S = (0.4, 2.0)
#: The steps :func:`step_period` looks for (seconds): half a stride.
STEP_RANGE_S = (0.2, 1.0)
#: The slow part of the ankles' picture taken away before a stride or a step is read (a Gaussian's sigma,
#: seconds): a turn of the person or the camera changes how far apart the feet look over seconds, not per step.
GAIT_DETREND_S = 1.5


def _repeat(signal: np.ndarray, seen: np.ndarray, fps: float, range_s: tuple[float, float]) -> tuple[float, float]:
    """(lag in seconds, correlation) of the highest peak of ``signal``'s (F, k) autocorrelation within ``range_s``
    (cut to the clip's length), its slow part taken away first (:data:`GAIT_DETREND_S`); ``(nan, 0.0)`` with no
    peak there or ``seen`` true on fewer than half the frames."""
    from scipy.ndimage import gaussian_filter1d

    lo, hi = (int(round(s * fps)) for s in range_s) if fps and fps > 0 else (0, 0)
    hi = min(hi, len(signal) - 2)
    if lo < 2 or hi <= lo or seen.sum() < len(signal) / 2:
        return float("nan"), 0.0
    signal = np.where(seen[:, None], signal, np.median(signal[seen], axis=0))
    signal = signal - gaussian_filter1d(signal, GAIT_DETREND_S * fps, axis=0, mode="nearest")
    n = len(signal)
    corr = np.array([np.sum(signal[:n - k] * signal[k:]) for k in range(hi + 2)])
    if corr[0] <= 0:
        return float("nan"), 0.0
    corr = corr / corr[0]
    inner = np.arange(lo, hi + 1)
    peaks = inner[(corr[inner] > corr[inner - 1]) & (corr[inner] >= corr[inner + 1])]
    if peaks.size == 0:
        return float("nan"), 0.0
    best = peaks[np.argmax(corr[peaks])]
    return float(best / fps), float(corr[best])


def stride_period(xy: np.ndarray, fps: float) -> tuple[float, float]:
    """(the stride in seconds, how strongly it repeats: 1 the same picture every stride) read from the vector
    between the two ankles in the picture (:func:`_figure_vector`), within :data:`STRIDE_RANGE_S`.

    Why: the ankles' picture repeats once a stride whatever the camera does, as a turn or a zoom moves both feet
    together; so the stride tells a walk (1.08-1.33 s on the tune clips of ``bench/motion_bench.py``, with a
    detector's errors too) from a run (0.70-0.80 s), which the feet's stillness in the picture cannot when the
    camera moves.  Left and right exchanged every other stride in the tracks read as a stride twice as long:
    :func:`step_period` is blind to that."""
    vector = _figure_vector(xy, (FEET["r"],), (FEET["l"],))
    seen = np.isfinite(vector).all(axis=1)
    return _repeat(vector, seen, fps, STRIDE_RANGE_S)


def step_period(xy: np.ndarray, fps: float) -> tuple[float, float]:
    """(the step in seconds, how strongly it repeats) read from the outer product of the vector between the
    ankles with itself, within :data:`STEP_RANGE_S`: the same for either foot in front and with left and right
    exchanged, so it repeats once a step, or once a stride where the feet's sideways spacing dominates the
    picture (a person seen from the front).  A walk's step read 0.53-0.70 s on the tune clips of
    ``bench/motion_bench.py``, a run's 0.33-0.38 s or its stride."""
    vector = _figure_vector(xy, (FEET["r"],), (FEET["l"],))
    seen = np.isfinite(vector).all(axis=1)
    x, y = vector[:, 0], vector[:, 1]
    return _repeat(np.stack([x * x, y * y, np.sqrt(2.0) * x * y], axis=1), seen, fps, STEP_RANGE_S)
