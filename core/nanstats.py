"""NaN-aware statistics that return NaN for an all-missing slice without a warning.

Missing joints are NaN throughout the project, and a joint or frame with no observation at all is
normal input, not a numerical accident worth a RuntimeWarning.
"""

from __future__ import annotations

import warnings

import numpy as np


def nanmedian(a: np.ndarray, axis=None) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(a, axis=axis)


def nanmean(a: np.ndarray, axis=None) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(a, axis=axis)


def nanmax(a: np.ndarray, axis=None) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmax(a, axis=axis)


#: The median length of a 2D isotropic Gaussian residual in units of its per-axis sigma (Rayleigh:
#: sqrt(2 ln 2)); a robust noise level is a median residual norm over this.
RAYLEIGH_MEDIAN = 1.1774


def second_difference_sigma(d2: np.ndarray) -> float:
    """White noise's standard deviation from second differences ``x[t+1] - 2 x[t] + x[t-1]`` (any shape,
    finite values): their robust spread (1.4826 x median |d2|) over sqrt(6), their sd in noise units."""
    return float(1.4826 * np.median(np.abs(d2)) / np.sqrt(6.0))
