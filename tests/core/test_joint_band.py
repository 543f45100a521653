"""The banded Gauss-Newton step of the joint solve against a dense solve (core.joint_solve.solver)."""

import numpy as np
import pytest
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


def _every_term(prob, x, n, fixed):
    """``prob`` with every optional term switched on: static scene points, a depth cue, a camera prior with a
    still spell, a standing person's hips and feet, and either fixed lengths with anchored frames or a length prior."""
    rng = np.random.default_rng(7)
    _, w, g, lengths = slv.unpack(x, n)
    dirs = rng.normal([0.0, 0.0, 1.0], 0.3, (6, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    R, _ = slv.rot_and_left_jacobian(w)
    Y = np.einsum("fab,sb->fsa", R, dirs)
    film = np.exp(g)[:, None, None] * Y[..., :2] / Y[..., 2:] + rng.normal(0, 0.05, (n, 6, 2))
    film[rng.random((n, 6)) < 0.3] = np.nan
    prob.static = {"film": film, "dirs": dirs}
    cue = rng.normal(size=(n, 16, 3))
    cue /= np.linalg.norm(cue, axis=-1, keepdims=True)
    cue[rng.random((n, 16)) < 0.2] = np.nan
    prob.bone_cue = {"dirs": cue, "sigma": 0.3}
    still = np.zeros(n, dtype=bool)
    still[3:8] = True
    prob.camera_prior = {"w": w + 0.01, "g": g - 0.02, "sigma_deg": 1.0, "sigma_log": 0.05, "still": still,
                         "still_sigma_deg": 0.1, "still_sigma_log": 0.01}
    feet = np.zeros((n, 2), dtype=bool)
    feet[2:9, 0] = feet[5:12, 1] = True
    prob.standing = {"accel_ms2": 2.5, "feet": feet}
    if fixed:
        prob.fixed_lengths = lengths.copy()
        frames = np.array([0, n - 1])
        X = slv.unpack(x, n)[0]
        prob.anchors = {"frames": frames, "w": w[frames], "g": g[frames], "x": X[frames] + 0.01}
    else:
        prob.length_prior = (lengths * 1.01, 0.01, 0.02)
    return prob


@pytest.mark.parametrize("fixed", [False, True])
def test_normal_equations_from_the_blocks_equal_the_sparse_products(fixed):
    # J^T J and J^T r summed from the builder's blocks, against scipy's products of the assembled Jacobian;
    # twice with one instance (the second time on the first call's plan), then on a problem with other
    # columns (fewer observed joints: a new plan)
    prob, x, truth = _problem(n=12)
    n = truth.n_frames
    prob = _every_term(prob, x, n, fixed)
    normal = slv._NormalEquations()
    nb = x.size - slv.N_GLOBAL
    rng = np.random.default_rng(3)
    for k in range(3):
        if k == 2:
            prob.film = prob.film.copy()
            prob.film[rng.random(prob.film.shape[:2]) < 0.2] = np.nan
        xk = x + rng.normal(0, 1e-3, x.size) * (k > 0)
        _, terms = slv._terms(prob, xk, True, None)
        band, grad = normal(terms, x.size, nb)
        r, jac = terms.build(x.size)
        A = (jac.T @ jac).toarray()
        # summation order aside, each entry is exact: bound the difference by eps-sized shares of |J|^T |J|
        scale = (abs(jac).T @ abs(jac)).toarray()
        L = band.lower.toarray()
        got = np.block([[L + L.T - np.diag(np.diag(L)), band.C], [band.C.T, band.D]])
        assert np.all(np.abs(got - A) <= 1e-12 * scale)
        assert np.all(np.abs(grad - jac.T @ r) <= 1e-12 * (abs(jac).T @ abs(r)))
        assert np.array_equal(band.diagonal(), np.diag(got))
        v = rng.normal(size=x.size)
        assert np.allclose(band.matvec(v), A @ v, rtol=0, atol=1e-12 * np.abs(A).max() * np.abs(v).max())
        # the band as LAPACK stores it: the half-width of the sparse product's, every entry in its place
        assert band.u == slv._Band.from_matrix(sp.csr_matrix(A), nb).u
        ab = band._band(np.float64)
        for d in range(band.u + 1):
            assert np.array_equal(ab[band.u - d, d:], np.diag(got[:nb, :nb], d))
    assert np.isfinite(grad).all() and np.abs(grad).max() > 0


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
