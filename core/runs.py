"""Runs of True in a boolean series: stances, camera spells, contacts, problem frames."""

from __future__ import annotations

import numpy as np


def runs(mask) -> list[tuple[int, int]]:
    """(start, end_exclusive) of every run of True in a 1D bool array."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def run_starts(mask) -> list[int]:
    """First index of every run of True in ``mask``."""
    return [int(a) for a, _ in runs(mask)]
