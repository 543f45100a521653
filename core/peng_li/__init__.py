"""Peng & Li (2006), "Human skeleton modeling from 2D uncalibrated monocular data": the baseline estimator.

One module per step of the paper; :func:`core.peng_li.pipeline.estimate_paper` runs them all.
"""
