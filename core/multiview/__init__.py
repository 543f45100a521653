"""Several synchronized views of one person (D'Apuzzo et al. 1999's setting) on the 17-joint tracks.

Where one camera leaves the depth of every limb to be inferred, two or more see it: the joints are
triangulated, and the cameras, when not given, are calibrated from the person himself (no board).
Entry point: :func:`estimate_multiview`; ``python -m core estimate-multiview VIEW1 VIEW2 ...``.
"""

from .cameras import ViewCamera, read_calibration, write_calibration
from .pipeline import estimate_multiview

__all__ = ["ViewCamera", "estimate_multiview", "read_calibration", "write_calibration"]
