"""One entry point for every estimator: :func:`estimate` and the ``METHODS`` registry.

Methods are imported lazily so that a front end which only reads files does
not pay for the solvers.  Each method is a callable
``fn(tracks, *, focal_mm=None, height_m=1.75, progress=None, should_cancel=None) -> Estimate``.

* ``progress(fraction, message)`` is called now and then with 0 <= fraction <= 1.
* ``should_cancel()`` is polled; when it returns True the method raises
  :class:`core.errors.Cancelled`.
* ``focal_mm`` is the user's focal length hint (36 mm film equivalent) or None.

When the user gives none, the lens the footage recorded (a detector run keeps it in the tracks'
``meta``: :mod:`core.lens`) is the hint instead; ``diagnostics["lens"]`` says which was used and
where it came from.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

import numpy as np

from .errors import InputError
from .joint_solve.blas_threads import single_blas_thread
from .lens.prior import META_FOCAL_ASSUMED
from .motion_cleanup import DEFAULT_CLEANUP, CleanupSettings, clean_estimate
from .result import Estimate
from .self_check import check_estimate
from .timebase import decimation_factor, to_full_rate, to_working_rate
from .track_cleaning import CleaningSettings, clean_tracks
from .track_cleaning.clean import DEFAULT_CLEANING
from .track_cleaning.residual import DEFAULT_RESIDUAL, ResidualSettings, found_detector_errors, residual_outliers
from .tracks import Tracks

#: name -> ("module relative to core", "function"), best method first.
METHODS: dict[str, tuple[str, str]] = {
    "joint": (".joint_solve.pipeline", "estimate_joint"),
    "paper": (".peng_li.pipeline", "estimate_paper"),
}
#: What runs when no method is named: the best one the project has.  "joint" since it was measured
#: better on proportions than "paper" at 0, 1 and 2 px noise over the 14 shared clips and the built-in
#: walk (mean 0.21/0.28/0.45 pp against 0.23/0.36/0.56; README "Accuracy"), and it alone gives 3D motion.
DEFAULT_METHOD = "joint"

METHOD_LABELS: dict[str, str] = {
    "joint": "Joint least squares (all frames, 3D motion)",
    "paper": "Peng & Li 2006 (baseline, proportions only)",
}


def method_function(name: str) -> Callable[..., Estimate]:
    if name not in METHODS:
        raise InputError(f"unknown method {name!r}; choose one of {sorted(METHODS)}")
    module_name, func = METHODS[name]
    module = importlib.import_module(module_name, __package__)
    return getattr(module, func)


def estimate(tracks: Tracks, method: str | None = None, *, focal_mm: float | None = None,
             height_m: float = 1.75, progress=None, should_cancel=None,
             cleaning: CleaningSettings | None = DEFAULT_CLEANING, working_rate: bool = True,
             background: bool = True, residual: ResidualSettings | None = DEFAULT_RESIDUAL,
             motion_cleanup: CleanupSettings | None = DEFAULT_CLEANUP) -> Estimate:
    """Run ``method`` (default :data:`DEFAULT_METHOD`) on ``tracks``.

    Every method gets the same preparation and the same self-check: the raw tracks are cleaned
    (:mod:`core.track_cleaning`; ``cleaning=None`` skips it), brought to the working frame rate
    (:mod:`core.timebase`; ``working_rate=False`` keeps the input's), estimated, brought back to
    every input frame, and checked (:mod:`core.self_check`): each frame says which joints were
    rejected or swapped, and ``diagnostics["self_check"]`` holds the flags, also in the warnings.
    When the cleaning found a detector's gross errors and the method solves 3D joints, the points
    its answer leaves unexplained are rejected and it solves once more without them
    (:mod:`core.track_cleaning.residual`; ``residual=None`` skips that second pass; so does
    ``cleaning=None``).
    ``background=False`` ignores the tracks' static background points (the camera from the person alone).
    ``motion_cleanup``: where the method solved 3D motion, planted feet are then held still in it
    (:mod:`core.motion_cleanup`), after any second pass (which must judge the solve's own fit) and
    before the self-check (which measures the fit of what is returned); None gives the raw solve.
    """
    name = method or DEFAULT_METHOD
    fn = method_function(name)
    if focal_mm is not None and not (focal_mm > 0):
        raise InputError(f"focal length must be positive, got {focal_mm!r} mm")
    focal_mm, lens = _lens_hint(tracks, focal_mm)
    if not (height_m > 0):
        raise InputError(f"height must be positive, got {height_m!r} m")
    report = None
    if not background and tracks.static is not None:
        tracks = tracks.replaced(static=None)
    prepared = tracks
    if cleaning is not None:
        prepared, report = clean_tracks(tracks, cleaning)
    k = decimation_factor(prepared.fps, prepared.n_frames) if working_rate else 1
    # only where the cleaning found a detector's gross errors: on clean tracks the points a solve leaves
    # unexplained are true ones its priors cannot follow (fast limbs), and dropping them costs accuracy
    detector = found_detector_errors(report, tracks, residual or DEFAULT_RESIDUAL)
    second_pass = detector and residual is not None
    if detector:
        # a detector's tracks: the methods may read them more warily (the joint method's length start)
        prepared = prepared.replaced(meta={**prepared.meta, "detector_errors": True})
    if lens is not None and lens.get("assumed"):
        # a phone's main camera, not a stated lens: background tracks that show the lens overrule it
        prepared = prepared.replaced(meta={**prepared.meta, META_FOCAL_ASSUMED: True})

    def solve(clip: Tracks, share: tuple[float, float]) -> Estimate:
        heard = progress
        if progress is not None and share != (0.0, 1.0):
            def heard(fraction, message=""):
                progress(share[0] + (share[1] - share[0]) * fraction, message)
        # one BLAS thread: numpy's products here are small, and OpenBLAS's second thread spends a third
        # of the process's CPU time waiting on them for no gain in wall time (docs/speed.md)
        with single_blas_thread():
            out = fn(to_working_rate(clip, k), focal_mm=focal_mm, height_m=height_m, progress=heard,
                     should_cancel=should_cancel)
        return to_full_rate(out, k, tracks.n_frames)

    est = solve(prepared, (0.0, 0.5) if second_pass else (0.0, 1.0))
    if second_pass:
        unexplained = residual_outliers(prepared, est, residual)
        if unexplained is not None and unexplained.any():
            prepared = prepared.replaced(xy=np.where(unexplained[..., None], np.nan, prepared.xy),
                                         conf=np.where(unexplained, 0.0, prepared.conf))
            report.residual = unexplained
            est = solve(prepared, (0.5, 1.0))
        elif progress is not None:
            progress(1.0, "")
    if motion_cleanup is not None:
        clean_estimate(est, tracks.fps, motion_cleanup)
    summary = None
    if report is not None:
        summary = report.summary(int(tracks.present.sum()))
        est.diagnostics["cleaning"] = summary
        for fr, rejected, swapped in zip(est.frames, *report.per_frame(), strict=True):
            fr.rejected = rejected or None
            fr.swapped = swapped or None
    check = check_estimate(est, prepared, summary, raw=tracks)
    est.diagnostics["self_check"] = check
    est.diagnostics["trusted"] = not check["flags"]
    warnings = est.diagnostics.setdefault("warnings", [])
    warnings.extend(fl["message"] for fl in check["flags"] if not fl.get("from_method"))
    if lens is not None:
        est.diagnostics["lens"] = lens
        if lens.get("assumed"):
            warnings.append(f"lens: {lens['source']}; a zoomed or wide-angle shot is further from it - give the "
                            "focal length if known")
    # the clip's picture and clock travel with the result (the build and the review report read them)
    est.diagnostics.setdefault("image_size", [float(v) for v in tracks.image_size])
    if tracks.fps:
        est.diagnostics.setdefault("fps", float(tracks.fps))
    return est


def _lens_hint(tracks: Tracks, focal_mm: float | None) -> tuple[float | None, dict | None]:
    """The focal hint to use and the ``diagnostics["lens"]`` entry: the user's focal length always wins;
    without it, the lens the footage recorded (:func:`core.lens.prior.lens_prior`), if any."""
    from .lens.prior import lens_prior

    recorded = lens_prior(tracks.meta)
    if focal_mm is not None:
        source = "the focal length given"
        if recorded is not None:
            source += f" (the footage's {recorded.focal_mm:.1f} mm, from {recorded.source}, not used)"
        return focal_mm, {"focal_mm": float(focal_mm), "source": source}
    if recorded is None:
        return None, None
    entry = {"focal_mm": recorded.focal_mm, "source": recorded.source}
    if recorded.assumed:
        entry["assumed"] = True
    return recorded.focal_mm, entry
