"""A handheld camera operator: overlapping pans, tilts and zooms at random times, and hand shake.

Moves arrive at random (on average ``moves_per_s``), each a pan of 2-25 degrees and/or a tilt of
1-8 degrees and/or a zoom of 10-40 %, lasting 0.4-3 s with a cosine ease; they overlap freely.  The
operator keeps the person in the picture: a pan or tilt turns towards the figure's image centre
more often than away from it, and the accumulated angles stay within limits.  Shake is a sum of
random sinusoids of 0.5-6 Hz with ``shake_deg`` standard deviation per axis.  Everything is in
seconds and degrees, so the same operator films at any frame rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..synth_camera import Spell


@dataclass(frozen=True)
class HandheldOperator:
    moves_per_s: float = 0.5
    pan_range_deg: tuple[float, float] = (2.0, 25.0)
    tilt_range_deg: tuple[float, float] = (1.0, 8.0)
    zoom_range: tuple[float, float] = (1.10, 1.40)
    duration_range_s: tuple[float, float] = (0.4, 3.0)
    pan_limit_deg: float = 35.0
    tilt_limit_deg: float = 12.0
    focal_ratio_limits: tuple[float, float] = (0.7, 1.8)
    shake_deg: float = 0.15
    #: The operator walks sideways (along frame 0's camera x axis) at this speed, m/s: a camera that
    #: translates, which the estimators do not model; the scene camera must notice it (parallax).
    walk_m_s: float = 0.0


def _ease(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * u))


def _shake(n: int, fps: float, sd_deg: float, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) pan/tilt/roll shake in degrees: random sinusoids, 0.5-6 Hz, ``sd_deg`` per axis."""
    t = np.arange(n) / fps
    out = np.zeros((n, 3))
    if sd_deg <= 0:
        return out
    for axis, share in ((0, 1.0), (1, 1.0), (2, 0.4)):
        k = 6
        freq = rng.uniform(0.5, 6.0, k)
        phase = rng.uniform(0, 2 * np.pi, k)
        amp = rng.normal(0.0, 1.0, k) / np.sqrt(freq)          # more slow wobble than fast tremor
        wave = (amp[None] * np.sin(2 * np.pi * freq[None] * t[:, None] + phase[None])).sum(axis=1)
        sd = np.sqrt(0.5 * np.sum(amp ** 2))
        out[:, axis] = wave * (share * sd_deg / max(sd, 1e-12))
    return out


def handheld_camera(n: int, fps: float, focal_mm: float, figure_offset_deg, seed: int,
                    operator: HandheldOperator = HandheldOperator()):
    """(angles (n, 3) degrees, focal (n,) mm, spells) of one random handheld take.

    ``figure_offset_deg(frame) -> (pan, tilt)``: where the figure's centre is, in degrees from the
    optical axis of frame 0's camera (the operator turns towards it).  ``spells`` cover the clip:
    still where no move is under way (shake aside), else ``pan_tilt`` or ``rotate_zoom``.
    """
    rng = np.random.default_rng([int(seed), 0x4A4D])
    t = np.arange(n) / fps
    angles = np.zeros((n, 3))
    log_f = np.full(n, math.log(focal_mm))
    active = np.zeros(n, dtype=bool)
    zooming = np.zeros(n, dtype=bool)
    def wait() -> float:                         # an operator who never moves only shakes
        return float(rng.exponential(1.0 / operator.moves_per_s)) if operator.moves_per_s > 0 else math.inf

    start = wait() * 0.5
    pan = tilt = 0.0
    ratio = 1.0
    while n and start < t[-1]:
        dur = float(rng.uniform(*operator.duration_range_s))
        kind = rng.choice(["pan", "tilt", "pan_tilt", "zoom", "pan_zoom"], p=[0.35, 0.15, 0.25, 0.1, 0.15])
        k0 = int(round(start * fps))
        fig_pan, fig_tilt = figure_offset_deg(min(n - 1, k0))
        d = np.zeros(3)
        if "pan" in kind:
            toward = math.copysign(1.0, fig_pan - pan) if abs(fig_pan - pan) > 1e-6 else 1.0
            sign = toward if rng.random() < 0.75 else -toward
            amp = float(rng.uniform(*operator.pan_range_deg))
            d[0] = float(np.clip(pan + sign * amp, -operator.pan_limit_deg, operator.pan_limit_deg) - pan)
        if "tilt" in kind:
            toward = math.copysign(1.0, fig_tilt - tilt) if abs(fig_tilt - tilt) > 1e-6 else 1.0
            sign = toward if rng.random() < 0.75 else -toward
            amp = float(rng.uniform(*operator.tilt_range_deg))
            d[1] = float(np.clip(tilt + sign * amp, -operator.tilt_limit_deg, operator.tilt_limit_deg) - tilt)
        dz = 0.0
        if "zoom" in kind:
            r = float(rng.uniform(*operator.zoom_range))
            lo, hi = operator.focal_ratio_limits
            r = r if (ratio * r <= hi and (ratio / r < lo or rng.random() < 0.5)) else 1.0 / r
            dz = math.log(float(np.clip(ratio * r, lo, hi)) / ratio)
        p = _ease((t - start) / dur)
        angles += p[:, None] * d[None]
        log_f += p * dz
        during = (t >= start) & (t <= start + dur)
        active |= during & (np.abs(d).sum() > 0 or dz != 0.0)
        zooming |= during & (dz != 0.0)
        pan += d[0]
        tilt += d[1]
        ratio *= math.exp(dz)
        start += wait()
    angles += _shake(n, fps, operator.shake_deg, rng)
    return angles, np.exp(log_f), _spells(active, zooming, angles, log_f)


def _spells(active: np.ndarray, zooming: np.ndarray, angles: np.ndarray, log_f: np.ndarray) -> list[Spell]:
    n = active.size
    spells: list[Spell] = []
    a = 0
    while a < n:
        b = a
        while b + 1 < n and active[b + 1] == active[a]:
            b += 1
        if active[a]:
            before = a - 1 if a > 0 else a
            delta = angles[b] - angles[before]
            params = {"pan_deg": float(delta[0]), "tilt_deg": float(delta[1]), "roll_deg": float(delta[2])}
            kind = "pan_tilt"
            if zooming[a:b + 1].any():
                kind = "rotate_zoom"
                params["zoom"] = float(math.exp(log_f[b] - log_f[before]))
            spells.append(Spell(a, b, kind, params))
        else:
            spells.append(Spell(a, b, "still"))
        a = b + 1
    return spells
