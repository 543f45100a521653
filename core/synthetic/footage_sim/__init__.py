"""What real footage does to the generator's clean film: a handheld operator and a 2D detector.

The paper's generator (:mod:`core.synthetic.synth`) films from a tripod that rests between single moves, and
reports every joint exactly, with Gaussian noise.  Users' footage is neither: :mod:`.handheld`
draws operators who pan, tilt and zoom whenever they like (moves overlap, no still spell is
promised) with hand shake on top, and :mod:`.detector` adds the errors of a real pose detector.
"""

from .detector import DetectorErrors, apply_detector_errors
from .handheld import HandheldOperator, handheld_camera

__all__ = ["DetectorErrors", "apply_detector_errors", "HandheldOperator", "handheld_camera"]
