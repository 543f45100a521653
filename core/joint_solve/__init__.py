"""The beyond-the-paper estimator: one joint least-squares solve over all frames.

Modules, one job each:

* :mod:`.taylor` – Taylor's (2000) single-image construction extended to a
  perspective camera: each segment's child lies on its viewing ray at one of
  two depths.
* :mod:`.signs_dp` – those two-way choices resolved over time per limb group
  by dynamic programming (Viterbi), with joint-limit and continuity costs.
* :mod:`.stance` – which foot is planted, from 2D (init) and from 3D (after a solve).
* :mod:`.camera_init` – camera rotation from the planted foot, to start the solve.
* :mod:`.solver` – the sparse Levenberg–Marquardt solve of every unknown at once.
* :mod:`.calibration` – focal self-calibration and its identifiability check.
* :mod:`.ground` – floor plane and up direction from the planted feet.
* :mod:`.pipeline` – :func:`estimate_joint`, the ``"joint"`` method.
"""
