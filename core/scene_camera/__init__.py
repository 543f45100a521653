"""The camera from the scene: rotation and focal length per frame from static background tracks.

From the person alone the focal length is not determined and a zoom looks like the person
coming nearer; a few tracked background points settle both.  The model is a
camera turning and zooming about a fixed centre (:mod:`.bundle`), solved by bundle adjustment
from a chained start (:mod:`.chain`) and checked by its own residuals (:mod:`.checks`);
:mod:`.solve` runs it for a clip.
"""

from .solve import SceneCamera, focal_arguments, solve_scene_camera

__all__ = ["SceneCamera", "focal_arguments", "solve_scene_camera"]
