"""A pose prior learnt from motion capture: how plausible a body pose is, used wherever a depth is guessed.

One picture of a person leaves every bone two depths (towards or away from the camera); the
estimators' geometric rules (knees bend backwards, continuity over time) leave about a third of the
frames with a mirrored limb.  This package scores poses by how often people take them:

* :mod:`.features` - a pose as its bones' directions in the body's own frame;
* :mod:`.model` - :class:`PosePrior` (a Gaussian mixture on those directions plus a term for their
  change over time), loaded from a ``.npz`` with numpy alone;
* :mod:`.train` - fitting it to BVH folders (``python -m core train-prior``).

:func:`load_default` returns the prior shipped in ``data/pose_prior.npz`` (trained on the CMU Graphics
Lab Motion Capture Database, mocap.cs.cmu.edu; ``docs/motion_prior.md``).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from .model import PosePrior

DEFAULT_PATH = Path(__file__).resolve().parent / "data" / "pose_prior.npz"


@lru_cache(maxsize=1)
def load_default() -> PosePrior:
    """The shipped prior (read once, then cached)."""
    return PosePrior.load(DEFAULT_PATH)


__all__ = ["DEFAULT_PATH", "PosePrior", "load_default"]
