"""Which ankle stands on the floor, frame by frame, read from the solved motion itself.

A planted ankle is low (not far above the frame's lower ankle) and slow in the world.  The
solve's own motion is noisy, so the decision has hysteresis: an ankle becomes planted when it is
slower than ``on_speed`` and lower than ``on_height``, and stays planted until it is faster than
``off_speed`` or higher than ``off_height``.  A contact shorter than ``min_contact_s`` is dropped (a
swing foot passing its lowest point).  Speeds and heights are in body heights (per second), times in
seconds, so one setting serves any stature and frame rate.

Both feet are decided apart (double support is two contacts at once), unlike the stance of
:mod:`core.joint_solve.stance`, which names one foot per frame for the solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..runs import runs
from ..skeleton import FEET


@dataclass(frozen=True)
class ContactSettings:
    on_speed: float = 0.15        # body heights per second: planted below this ...
    off_speed: float = 0.30       # ... until above this
    on_height: float = 0.06       # body heights above the low level (:attr:`low_level`): planted below this ...
    off_height: float = 0.09      # ... until above this
    min_contact_s: float = 0.1    # shorter contacts are dropped
    #: the speed is a running median over this time (noise, one bad frame).  0.2 s chosen on the tune half of
    #: ``bench/motion_bench.py`` (5 clips x 3 draws x 4 scenarios, ``bench/motion_replay.py``): the still
    #: camera's median |planted excess| 63 -> 43 mm/s against 0.1 s, the other scenarios unchanged (27, 69, 914);
    #: 0.3 s: 42, 27-29, 69, 914.
    speed_window_s: float = 0.2
    #: the ankles' low level: the lower ankle's lowest within this time around the frame, or 0: the clip's 5th
    #: percentile.  A local level (against a floor found a few degrees off, or a slope) measured no better on
    #: the tune half (median |planted excess| 1.5 s / 3 s / clip: paper 69 / 88 / 69, still 43 / 43 / 43,
    #: background 27 / 20 / 27, detector 964 / 914 / 914 mm/s), so the clip's level is used
    low_window_s: float = 0.0
    #: "frame": heights above the frame's lower ankle (the rule of :func:`core.joint_solve.stance.stance_from_world`,
    #: blind to a floor found tilted); "clip": above the clip's (or the window's) low level.  On the tune half
    #: (median |planted excess|, mm/s, paper / still / detector / background) the clip's level with 0.04 / 0.07
    #: gave 69 / 43 / 914 / 27, the frame's with 0.04 / 0.07 63 / 43 / 914 / 27, with 0.06 / 0.09 54 / 43 / 914
    #: / 27, with 0.02 / 0.04 69 / 43 / 944 / 27 (the paper schedule's planted ankles sat 13-25 cm above the
    #: clip's level in 3 of 8 of its cases looked at: likely a floor found tilted)
    low_level: str = "frame"


def _running_median(x: np.ndarray, k: int) -> np.ndarray:
    if k <= 1:
        return x
    half = k // 2
    pad = np.pad(x, ((half, half),) + ((0, 0),) * (x.ndim - 1), mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(pad, k, axis=0)
    return np.median(win, axis=-1)


def ankle_heights_speeds(ankles_world: np.ndarray, fps: float, height_m: float, window_s: float,
                         low_window_s: float = 0.0, low_level: str = "clip") -> tuple[np.ndarray, np.ndarray]:
    """(F, 2) heights above the ankles' low level and (F, 2) running-median speeds, in body heights (per
    second), of the ankles (F, 2, 3) in world axes, Z up.  The low level is the lower ankle's lowest within
    ``low_window_s`` around each frame (0: the clip's 5th percentile of both); with ``low_level="frame"``
    the frame's lower ankle."""
    z = ankles_world[..., 2]
    k_low = int(round(low_window_s * fps)) | 1
    if low_level == "frame":
        low = z.min(axis=1, keepdims=True)
    elif low_window_s > 0 and k_low < z.shape[0]:
        lower = z.min(axis=1)
        half = k_low // 2
        pad = np.pad(lower, (half, half), mode="edge")
        low = np.lib.stride_tricks.sliding_window_view(pad, k_low).min(axis=-1)[:, None]
    else:
        low = float(np.nanpercentile(z, 5.0))
    height = (z - low) / height_m
    n = ankles_world.shape[0]
    v = np.zeros((n, 2))
    if n >= 3:
        v[1:-1] = np.linalg.norm(ankles_world[2:] - ankles_world[:-2], axis=-1) * (fps / 2.0)
        v[0], v[-1] = v[1], v[-2]
    k = max(1, int(round(window_s * fps)) | 1)
    return height, _running_median(v, k) / height_m


def detect_contacts(joints_world: np.ndarray, fps: float, height_m: float,
                    settings: ContactSettings = ContactSettings()) -> np.ndarray:
    """(F, 2) bool, (left, right) ankle planted, from joints (F, 17, 3) in world axes (Z up)."""
    ankles = joints_world[:, [FEET["l"], FEET["r"]]]
    height, speed = ankle_heights_speeds(ankles, fps, height_m, settings.speed_window_s,
                                         settings.low_window_s, settings.low_level)
    n = ankles.shape[0]
    out = np.zeros((n, 2), dtype=bool)
    min_len = max(1, int(round(settings.min_contact_s * fps)))
    for s in range(2):
        on = (speed[:, s] < settings.on_speed) & (height[:, s] < settings.on_height)
        stay = (speed[:, s] <= settings.off_speed) & (height[:, s] <= settings.off_height)
        planted = False
        for i in range(n):
            planted = stay[i] if planted else on[i]
            out[i, s] = planted
        for a, end in runs(out[:, s]):
            if end - a < min_len:
                out[a:end, s] = False
    return out
