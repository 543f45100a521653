"""Refine Tracks on Footage: the detector's joints re-found by Blender's tracker and fused.

:mod:`.tracker` runs Blender's least-squares tracker from the detector's positions;
:mod:`core.track_refinement` plans the seeds and fuses the tracked motion with the detector.
"""

from __future__ import annotations

from ...core.track_refinement import FuseSettings, refine_tracks, seed_plan  # noqa: F401 - for callers
from .tracker import MOTION_MODELS, track_runs

__all__ = ["MOTION_MODELS", "refine_on_clip"]


def refine_on_clip(context, clip, tracks, *, first_clip_frame: int = 1, window: int = 5, motion_model: str = "Loc",
                   disagree: str = "detector", settings: FuseSettings | None = None, progress=None):
    """``tracks`` refined on ``clip``'s images: (new tracks, :class:`core.track_refinement.RefineReport`).

    ``first_clip_frame``: the clip frame of the tracks' first frame. ``window``: frames tracked from
    each seed (5: as good as 3 and better than 10 on painted footage, with fewer tracker calls;
    docs/track_refinement.md).
    """
    plan = seed_plan(tracks, window)
    runs = track_runs(context, clip, tracks, plan, window, first_clip_frame=first_clip_frame,
                      motion_model=motion_model, progress=progress)
    refined, report = refine_tracks(tracks, runs, settings=settings, disagree=disagree)
    refined.meta["refined"]["clip"] = clip.name
    refined.meta["refined"]["window"] = int(window)
    refined.meta["refined"]["motion_model"] = motion_model
    return refined, report
