"""Review of a result without Blender: reprojection residuals per joint, take comparison, the HTML report.

The Blender side (``blender/review``) draws these in the scene; ``batch.py`` and ``python -m core
report`` write the report beside the outputs so a folder of clips can be reviewed without opening Blender.
"""

from .residuals import reprojected_pixels, residual_colours, residual_lines
from .take_compare import TakeComparison, compare_takes

__all__ = ["TakeComparison", "compare_takes", "reprojected_pixels", "residual_colours", "residual_lines"]
