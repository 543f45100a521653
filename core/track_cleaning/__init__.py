"""Cleaning of raw 2D detector tracks before any estimator sees them.

Real detectors (OpenPose, MediaPipe, RTMPose, ViTPose) put a wrist on a table leg for a frame or
two, exchange the left and right legs while they cross, and now and then report a coordinate far
off the picture.  Every estimator assumes none of that, so :func:`clean_tracks` runs first, on the
tracks at their own frame rate, and says per frame what it changed:

1. :mod:`.sanity`: points far outside the image are treated as missing;
2. :mod:`.swaps`: left/right exchanges of a limb (or of the whole body) are found by continuity over
   time and undone;
3. :mod:`.outliers`: gross outliers (a joint thrown away from the body for a few frames) are found
   by a robust temporal fit together with the lengths of the joint's 2D bones, and made missing.

All windows are in seconds and all distances relative to the figure's own image size, so the
cleaning means the same at 24 or 240 fps and at any resolution.
"""

from .clean import CleaningReport, CleaningSettings, clean_tracks

__all__ = ["CleaningReport", "CleaningSettings", "clean_tracks"]
