"""Where motions come from: a BVH file or a built-in procedural clip.

Every consumer (the synthetic experiment, the Blender test-data operator,
the benchmarks) asks :func:`load_motion` for a :class:`Motion` and never
cares whether it came from a file.  A ``Motion`` is always a *rigid*,
left/right-symmetric canonical figure, so its proportions are exact truth.
"""

from __future__ import annotations

from .motion_clip import Motion

__all__ = ["BUILTIN_PREFIX", "Motion", "load_motion"]

BUILTIN_PREFIX = "builtin:"


def load_motion(source: str, *, height_m: float = 1.75, max_frames: int | None = None,
                fps: float | None = None) -> Motion:
    """A rigid canonical :class:`Motion` from ``source``.

    ``source`` is a path to a ``.bvh`` file or ``"builtin:NAME"`` (see
    :data:`core.synthetic.procedural.BUILTIN_MOTIONS`).  ``fps`` resamples (None keeps
    the source rate); ``max_frames`` truncates after resampling.  Bad input
    raises :class:`core.errors.InputError`.
    """
    if source.startswith(BUILTIN_PREFIX):
        from .procedural import builtin_motion

        motion = builtin_motion(source[len(BUILTIN_PREFIX):], height_m=height_m, fps=fps)
    else:
        from .rigid_figure import motion_from_bvh_file

        motion = motion_from_bvh_file(source, height_m=height_m, fps=fps)
    if max_frames is not None and motion.n_frames > max_frames:
        motion = Motion(motion.name, motion.fps, motion.joints[:max_frames],
                        motion.class_lengths, motion.contacts[:max_frames], dict(motion.meta))
    return motion
