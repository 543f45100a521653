"""The banded Gauss-Newton step of the joint solve against a dense solve (core.joint_solve.solver)."""

import numpy as np
import scipy.sparse as sp

from core import camera as cam
from core.joint_solve import solver as slv
from core.joint_solve.stance import stance_codes
from core.skeleton import class_lengths_for_height, proportions
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def _problem(n=12, **kw):
    motion = load_motion("builtin:walk", max_frames=n, fps=30.0)
    tracks, truth = synthesize(motion, kinds=("pan", "tilt", "zoom"), noise_px=1.0, seed=4, continuous=True,
                               dropout=0.1)
    st = stance_codes(truth.stance)
    prob = slv.Problem(cam.pixels_to_film(tracks.xy, tracks.image_size), cam.mm_per_pixel(tracks.image_size),
                       tracks.fps, truth.height_m, st, focal_prior_mm=50.0, **kw)
    rng = np.random.default_rng(5)
    x = slv.pack(truth.joints_3d + rng.normal(0, 0.02, truth.joints_3d.shape), np.radians(truth.rotvec_deg),
                 np.log(truth.focal_mm), truth.class_lengths_m * 1.02, stance=st)
    return prob, x, truth


def test_band_step_in_both_precisions_leaves_the_rhs_alone(monkeypatch):
    # the factor is single precision by default, refined with the double matrix; the double path is the
    # fallback.  Both must give the dense step, and neither may write into the caller's gradient (LAPACK's
    # overwrite_b on a column view of it did: the LM loop then used a corrupted gradient)
    prob, x, _ = _problem()
    _, r, jac = slv.residuals(prob, x)
    A = (jac.T @ jac).tocsr()
    grad = jac.T @ r
    damping = 1e-3 * A.diagonal() + 1e-9
    dense = np.linalg.solve(A.toarray() + np.diag(damping), grad)
    for single in (True, False):
        monkeypatch.setattr(slv, "SINGLE_PRECISION_FACTOR", single)
        g = grad.copy()
        step = slv._Band.from_matrix(A, x.size - slv.N_GLOBAL).solve(damping, g)
        assert np.array_equal(g, grad)
        assert np.allclose(step, dense, rtol=1e-6, atol=1e-9 * np.abs(dense).max())


def test_band_falls_back_to_double_precision():
    # positive definite, but singular once rounded to single precision: the double factor takes over
    e = 1e-9
    M = np.array([[1.0, 1.0 - e, 0.0, 0.0], [1.0 - e, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 2.0]])
    rhs = np.array([1.0, 2.0, 3.0, 4.0])
    step = slv._Band.from_matrix(sp.csr_matrix(M), 3).solve(np.zeros(4), rhs)
    assert np.allclose(step, np.linalg.solve(M, rhs), rtol=1e-6)


def test_band_rejects_an_indefinite_matrix():
    A = sp.csr_matrix(np.diag([1.0, -1.0, 1.0, 2.0]))
    try:
        slv._Band.from_matrix(A, 3).solve(np.zeros(4), np.ones(4))
    except np.linalg.LinAlgError:
        return
    raise AssertionError("an indefinite band must raise LinAlgError (the solver then raises the damping)")


def test_length_prior_pulls_the_lengths():
    target = None
    results = []
    for sigma in (None, 1e-4):
        prob, x, truth = _problem(n=20)
        # another estimate's lengths: 3 % off in shape, same standing height (the solve fixes the height)
        target = class_lengths_for_height(proportions(truth.class_lengths_m * np.linspace(0.97, 1.03, 10)),
                                          truth.height_m)
        if sigma is not None:
            prob.length_prior = (target, sigma)
        xs, _ = slv.solve(prob, x, max_iter=6)
        results.append(np.abs(slv.unpack(xs, truth.n_frames)[3] - target).max())
    assert results[1] < 0.2 * results[0]
    assert results[1] < 0.002



def test_length_prior_can_be_softer_above():
    # the paper's lengths are lower bounds: a third sigma softens the prior where a length exceeds them,
    # and only there (the cost of each length family is read from the residuals themselves)
    prob, x, truth = _problem(n=6)
    joints, w, g, _ = slv.unpack(x, truth.n_frames)
    target = truth.class_lengths_m.copy()
    costs = {}
    for sign in (+1, -1):
        for third in (None, 0.01):
            prob.length_prior = (target, 0.001) if third is None else (target, 0.001, third)
            parts: dict = {}
            xl = slv.pack(joints, w, g, target + sign * 0.002)
            slv.residuals(prob, xl, with_jac=False, parts=parts)
            costs[sign, third] = parts["length_prior"]
    assert costs[-1, None] == costs[-1, 0.01] == costs[+1, None]          # below, and symmetric: 2 mm / 1 mm
    assert np.isclose(costs[+1, None] / costs[+1, 0.01], 100.0, rtol=1e-6)    # above: (10 mm / 1 mm) squared


def test_length_prior_sigmas_can_differ_per_class():
    # one sigma per class: each class's share of the prior's cost is (offset / its own sigma)^2 / 2
    prob, x, truth = _problem(n=6)
    joints, w, g, _ = slv.unpack(x, truth.n_frames)
    target = truth.class_lengths_m.copy()
    sigmas = np.full(10, 0.001)
    sigmas[3] = 0.01
    prob.length_prior = (target, sigmas, sigmas)
    parts: dict = {}
    slv.residuals(prob, slv.pack(joints, w, g, target + 0.002), with_jac=False, parts=parts)
    assert np.isclose(parts["length_prior"], 0.5 * np.sum((0.002 / sigmas) ** 2), rtol=1e-9)


def test_joint_method_loosens_the_length_prior_only_for_the_upright_chain():
    from core.joint_solve import pipeline as pl
    from core.skeleton import CLASSES

    lengths = np.linspace(0.1, 0.5, 10)
    _, below, above = pl._length_prior({"proportions": np.ones(10)}, lengths)
    loose = {c for c, b, a in zip(CLASSES, below, above) if b == a == pl.UPRIGHT_LENGTH_PRIOR_SIGMA_M}
    assert loose == {"lower_spine", "upper_spine", "head"}
    assert all(b == pl.LENGTH_PRIOR_SIGMA_M and a == pl.LENGTH_PRIOR_SIGMA_ABOVE_M
               for c, b, a in zip(CLASSES, below, above) if c not in loose)
