"""Synthetic clips with known truth: where motions come from (BVH files or built-in procedural clips),
the rigid figure, the filming camera's schedules, the 2D tracks and truth they produce, and simulated
footage (painted frames, handheld operators, detector errors).

The benchmarks, the tests and the Blender test-data operator all make their clips here, so every
estimator is scored on the same material.
"""
