"""Step 1 (paper 3.1): 2D data rectification.

Joint trajectories of a person filmed by a smoothly moving camera are smooth over a
few frames, so the paper treats frame-to-frame jitter as extraction noise and
smooths it away.  Missing joints (NaN) would poison a filter, so short gaps are
first bridged by linear interpolation; long gaps stay missing and every later step
skips the frames that lack the joints it needs.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from ..runs import runs
from .params import PaperParams


def fill_short_gaps(series: np.ndarray, max_gap: int) -> np.ndarray:
    """Linearly interpolate NaN gaps of at most ``max_gap`` frames inside a 1D series."""
    out = series.copy()
    good = np.isfinite(series)
    if good.sum() < 2:
        return out
    idx = np.arange(series.size)
    interp = np.interp(idx, idx[good], series[good])
    for a, b in runs(~good):
        if a > 0 and b < series.size and b - a <= max_gap:  # interior gaps only
            out[a:b] = interp[a:b]
    return out


def savgol(series: np.ndarray, window: int, order: int) -> np.ndarray:
    """Savitzky-Golay smoothing of a 1D series: each sample replaced by the value at its centre of the
    least-squares polynomial of degree ``order`` through the ``window`` (odd) samples around it; the first
    and last ``window // 2`` samples by the polynomial fitted to the first (last) whole window (what
    ``scipy.signal.savgol_filter`` calls ``mode="interp"``).

    Why our own: ``scipy.signal`` takes about half a second to import (it pulls in ``scipy.stats``), paid
    on every estimate in a fresh process, for these few lines.
    """
    y = np.asarray(series, dtype=float)
    half = window // 2
    t = np.arange(-half, half + 1, dtype=float)
    vander = t[:, None] ** np.arange(order + 1)                 # (window, order + 1)
    fit = np.linalg.pinv(vander)                                # polynomial coefficients from a window
    out = np.convolve(y, fit[0][::-1], mode="same")             # the centre value: the constant term
    out[:half] = vander[:half] @ (fit @ y[:window])
    out[-half:] = vander[-half:] @ (fit @ y[-window:])
    return out


def smooth_series(series: np.ndarray, fps: float, params: PaperParams) -> np.ndarray:
    """Smooth each finite run of a 1D series separately (NaN stays NaN)."""
    out = series.copy()
    if params.smoothing == "none":
        return out
    for a, b in runs(np.isfinite(series)):
        seg = series[a:b]
        if params.smoothing == "gaussian":
            sigma = params.gaussian_sigma_s * fps
            if sigma > 0 and seg.size >= 3:
                out[a:b] = gaussian_filter1d(seg, sigma, mode="nearest")
        elif params.smoothing == "savgol":
            window = max(3, int(round(params.savgol_window_30fps * fps / 30.0)))
            window += 1 - window % 2
            window = min(window, seg.size if seg.size % 2 else seg.size - 1)
            if window > params.savgol_order + 1:
                out[a:b] = savgol(seg, window, params.savgol_order)
        else:
            raise ValueError(f"unknown smoothing {params.smoothing!r}")
    return out


def rectify(points: np.ndarray, fps: float, params: PaperParams) -> np.ndarray:
    """Gap-fill and smooth trajectories shaped (F, J, 2); returns a new array."""
    pts = np.asarray(points, dtype=float)
    out = np.empty_like(pts)
    max_gap = params.window_frames(params.max_gap_s, fps)
    flat_in = pts.reshape(pts.shape[0], -1)
    flat_out = out.reshape(pts.shape[0], -1)
    for k in range(flat_in.shape[1]):
        filled = fill_short_gaps(flat_in[:, k], max_gap)
        flat_out[:, k] = smooth_series(filled, fps, params)
    return out
