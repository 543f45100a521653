"""A pose prior learnt from motion capture: how plausible a body pose is, used wherever a depth is guessed.

One picture of a person leaves every bone two depths (towards or away from the camera); the
estimators' geometric rules (knees bend backwards, continuity over time) leave about a third of the
frames with a mirrored limb.  This package scores poses by how often people take them:

* :mod:`.features` - a pose as its bones' directions in the body's own frame;
* :mod:`.model` - :class:`PosePrior` (a Gaussian mixture on those directions plus a term for their
  change over time), loaded from a ``.npz`` with numpy alone;
* :mod:`.train` - fitting it to BVH folders (``python -m core train-prior``);
* :mod:`.lifter` - :class:`PoseLifter`, a small network reading one picture's joints for which way
  each bone points in depth; :mod:`.train_lifter` trains it (``python -m core train-lifter``).

:func:`load_default` returns the prior shipped in ``data/pose_prior.npz`` (trained on the CMU Graphics
Lab Motion Capture Database, mocap.cs.cmu.edu; ``docs/motion_prior.md``).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from .lifter import PoseLifter
from .model import PosePrior

DEFAULT_PATH = Path(__file__).resolve().parent / "data" / "pose_prior.npz"
DEFAULT_LIFTER_PATH = Path(__file__).resolve().parent / "data" / "pose_lifter.npz"
DEFAULT_VIDEO_LIFTER_PATH = Path(__file__).resolve().parent / "data" / "pose_lifter_video.npz"


@lru_cache(maxsize=1)
def load_default() -> PosePrior:
    """The shipped prior (read once, then cached)."""
    return PosePrior.load(DEFAULT_PATH)


@lru_cache(maxsize=1)
def load_default_lifter() -> PoseLifter:
    """The shipped lifter (read once, then cached)."""
    return PoseLifter.load(DEFAULT_LIFTER_PATH)


@lru_cache(maxsize=1)
def load_video_lifter() -> PoseLifter:
    """The lifter the joint solve reads consecutive frames with: the shipped temporal one where there is
    one, else :func:`load_default_lifter` (read once, then cached)."""
    path = Path(DEFAULT_VIDEO_LIFTER_PATH)
    return PoseLifter.load(path) if path.is_file() else load_default_lifter()


__all__ = ["DEFAULT_LIFTER_PATH", "DEFAULT_PATH", "DEFAULT_VIDEO_LIFTER_PATH", "PoseLifter", "PosePrior",
           "load_default", "load_default_lifter", "load_video_lifter"]
