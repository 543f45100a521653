"""Track Background: static scene features found and followed on the footage by Blender's tracker.

:mod:`.follow` runs Blender's corner detector and tracker on a Movie Clip; :mod:`core.background_tracking`
decides where features may be seeded and which are kept. The result is the joint tracks' static tracks,
which give the camera its turn and zoom (``core.scene_camera``).
"""

from __future__ import annotations

from .follow import BG_PREFIX, track_background

__all__ = ["BG_PREFIX", "track_background"]
