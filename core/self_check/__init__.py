"""The estimate checks itself against the tracks it came from, and says when not to trust it.

:func:`check_estimate` measures what the answer explains of the tracks (robust reprojection
residuals per joint and frame against the 2D noise the tracks show), how much of the input the
cleaning had to set aside, how well the camera could be observed (how far it turned while the focal
length was only assumed, how much of the clip shows a planted foot), and whether the bones the
tracks need stay within the lengths found.  Each failed check is a *flag* with a code and one plain
sentence; the flags join the result's warnings and the sidebar.  Thresholds were chosen on the tuning
half of ``bench/robust_bench.py`` only (``docs/robustness.md``).
"""

from .checks import SelfCheckSettings, check_estimate
from .reprojection import camera_points, reprojection_residuals

__all__ = ["SelfCheckSettings", "camera_points", "check_estimate", "reprojection_residuals"]
