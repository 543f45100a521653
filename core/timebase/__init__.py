"""One working frame rate for every estimator, whatever rate the footage was filmed at.

The estimators' windows, priors and per-frame costs were built and measured at video rates
(24-30 fps); at 120 fps a pan moves the picture a quarter as far per frame and slipped under
thresholds made for 30.  Rather than re-deriving every per-frame quantity, footage above about
1.5x the working rate is averaged and decimated to it (120 fps -> 30, 60 -> 30, 50 -> 25,
240 -> 30) before estimation, and the result is brought back to every input frame: camera and
focal interpolated, bones turned between the working frames at their fixed lengths.  Averaging k
frames also divides the 2D noise by sqrt(k), so faster footage costs less time and gives no less.
"""

from .working_rate import WORKING_FPS, decimation_factor, to_full_rate, to_working_rate

__all__ = ["WORKING_FPS", "decimation_factor", "to_full_rate", "to_working_rate"]
