"""Problems on the timeline: what the estimate says about each frame, as markers an animator
sees while scrubbing.

Markers mark the first frame of each run of frames where joints were set aside as outliers
(``input: rejected joints``), where left and right were swapped back (``input: left/right undone``)
and where the solved figure fits the tracks poorly (``fit: poor``: a frame's mean reprojection error over
the self-check's limits, :mod:`core.review.problems`), beside the camera spells (``camera: ...``,
:mod:`.build_camera`).  A rebuild prunes the markers of an earlier estimate (:func:`prune_markers`).
"""

from __future__ import annotations

from ...core.review.problems import problem_starts
from ..build_camera import add_markers, spell_markers

PREFIXES = ("camera: ", "input: ", "fit: ")
__all__ = ["PREFIXES", "expected_markers", "mark_problems", "problem_markers", "prune_markers"]


def problem_markers(est, first_frame: int) -> list[tuple[str, int]]:
    """(name, scene frame) of every problem run's first frame."""
    return [(name, i + first_frame) for name, i in problem_starts(est)]


def mark_problems(scene, est, first_frame: int, created: list) -> int:
    """Add the problem markers (an existing one with the same name and frame is kept); returns how many."""
    return add_markers(scene, problem_markers(est, first_frame), created)


def prune_markers(scene, keep: set) -> int:
    """Remove this add-on's markers (by :data:`PREFIXES`) that are not in ``keep`` {(name, frame)}."""
    stale = [m for m in scene.timeline_markers if m.name.startswith(PREFIXES) and (m.name, m.frame) not in keep]
    for m in stale:
        scene.timeline_markers.remove(m)
    return len(stale)


def expected_markers(est, first_frame: int) -> set:
    """Every marker a build of ``est`` makes: the camera spells and the problems."""
    spells = spell_markers((est.diagnostics or {}).get("spells"), first_frame)
    return set(problem_markers(est, first_frame)) | set(spells)
