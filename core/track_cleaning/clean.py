""":func:`clean_tracks`: the three cleaning steps in order, and the report of what they changed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..skeleton import JOINTS, LIMB_PAIRS
from ..tracks import Tracks
from .body_scale import body_scale
from .outliers import find_outliers
from .sanity import far_outside
from .swaps import apply_swaps, swap_states

#: Names of the swap depths in reports, per pair (index = joints exchanged from the limb's end).
SWAP_NAMES = {
    "legs": ("", "ankles", "knees+ankles", "legs"),
    "arms": ("", "wrists", "elbows+wrists", "arms"),
}


@dataclass(frozen=True)
class CleaningSettings:
    """Every threshold of the cleaning; distances in body scales (median 2D segment), times in seconds.

    Chosen on the tuning half of ``bench/robust_bench.py``'s cases only (``docs/robustness.md``).
    """

    #: A point more than this many image sizes outside the picture is missing.
    outside_margin: float = 1.0
    #: Swaps: price of one second of exchanged frames, and the cap of one joint's squared jump.
    swap_price_per_s: float = 30.0
    swap_cap: float = 25.0
    #: Outliers: running-median window, residual (with a stretched bone) and residual alone.
    outlier_window_s: float = 0.25
    outlier_residual: float = 1.0
    outlier_stretch: float = 1.8
    outlier_residual_alone: float = 4.0
    #: Turn a step off (for comparisons and the baseline "raw" runs).
    swaps: bool = True
    outliers: bool = True


DEFAULT_CLEANING = CleaningSettings()


@dataclass
class CleaningReport:
    """What :func:`clean_tracks` changed, per frame."""

    outside: np.ndarray                      # (F, 17) bool: far outside the image, made missing
    outliers: np.ndarray                     # (F, 17) bool: gross outliers, made missing
    swaps: dict[str, np.ndarray] = field(default_factory=dict)  # pair -> (F,) exchanged depth
    #: (F, 17) bool: points the first solve could not explain, made missing for the second
    #: (:mod:`.residual`); None when there was no second pass.
    residual: np.ndarray | None = None

    @property
    def rejected(self) -> np.ndarray:
        out = self.outside | self.outliers
        return out if self.residual is None else out | self.residual

    def gross_share(self, observed: int) -> float:
        """Share of the observed points the cleaning itself rejected (far outside, gross outliers)."""
        return float((self.outside | self.outliers).sum() / max(observed, 1))

    def swapped_frames(self) -> np.ndarray:
        out = np.zeros(self.outside.shape[0], dtype=bool)
        for depth in self.swaps.values():
            out |= depth > 0
        return out

    def per_frame(self) -> tuple[list[list[str]], list[list[str]]]:
        """Per frame, the names of the joints rejected and of the exchanges undone (empty lists where none)."""
        rejected = self.rejected
        names = [[JOINTS[j] for j in np.flatnonzero(row)] for row in rejected]
        swapped: list[list[str]] = [[] for _ in range(rejected.shape[0])]
        for p, depth in self.swaps.items():
            for f in np.flatnonzero(depth > 0):
                swapped[f].append(SWAP_NAMES[p][int(depth[f])])
        return names, swapped

    def summary(self, observed: int) -> dict:
        """Counts for the result's diagnostics (``observed``: joint entries the detector gave)."""
        n = self.outside.shape[0]
        swapped = int(self.swapped_frames().sum())
        return {
            "observed_points": int(observed),
            "outside_image": int(self.outside.sum()),
            "outliers": int(self.outliers.sum()),
            # the share the self-check judges is the cleaning's own (2D evidence): the second pass's
            # rejections are counted apart, since some are points a correct answer cannot reach
            "rejected_share": self.gross_share(observed),
            "unexplained": int(0 if self.residual is None else self.residual.sum()),
            "swapped_frames": swapped,
            "swapped_share": float(swapped / max(n, 1)),
        }


def clean_tracks(tracks: Tracks, settings: CleaningSettings = DEFAULT_CLEANING) -> tuple[Tracks, CleaningReport]:
    """Tracks with far-off points and outliers missing and left/right exchanges undone, and the report."""
    xy = tracks.xy.copy()
    conf = tracks.conf.copy()
    n = tracks.n_frames
    outside = far_outside(xy, tracks.image_size, settings.outside_margin)
    xy[outside] = np.nan
    conf[outside] = 0.0
    scale = body_scale(xy, tracks.fps)
    outliers = np.zeros_like(outside)
    swaps: dict[str, np.ndarray] = {}
    if np.isfinite(scale).all() and n >= 3:
        if settings.swaps:
            for pair in LIMB_PAIRS:
                swaps[pair] = swap_states(xy, scale, tracks.fps, pair, price_per_s=settings.swap_price_per_s,
                                          cap=settings.swap_cap)
            xy, conf = apply_swaps(xy, conf, swaps)
        if settings.outliers:
            outliers = find_outliers(xy, scale, tracks.fps, window_s=settings.outlier_window_s,
                                     residual=settings.outlier_residual, stretch=settings.outlier_stretch,
                                     residual_alone=settings.outlier_residual_alone)
            xy[outliers] = np.nan
            conf[outliers] = 0.0
    meta = dict(tracks.meta)
    cleaned = tracks.replaced(xy=xy, conf=conf, meta=meta)
    return cleaned, CleaningReport(outside=outside, outliers=outliers, swaps=swaps)
