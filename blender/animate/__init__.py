"""Animate from Clip: footage in, an animated armature and camera out, in one run that can be stopped.

:mod:`.chain` steps the long parts (detecting the pose, following the background, estimating) a piece at
a time and keeps what they find in memory, so a cancel or a failure leaves the scene as it was;
:mod:`.snapshot` puts the scene back if putting the result into it fails part way.
"""

from .chain import AnimateOptions, AnimateRun
from .snapshot import SceneSnapshot

__all__ = ["AnimateOptions", "AnimateRun", "SceneSnapshot"]
