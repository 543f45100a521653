"""Fixtures shared by the core tests."""

import importlib.util
from pathlib import Path

import pytest

BENCH_DIR = Path(__file__).resolve().parents[2] / "bench"


@pytest.fixture(scope="session")
def load_bench():
    """``load(file_name)``: a script of ``bench/`` imported as a module, so a test can call its functions."""

    def load(file_name: str):
        spec = importlib.util.spec_from_file_location(Path(file_name).stem + "_bench", BENCH_DIR / file_name)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture
def check_cost_gradient():
    """``check(prob, x, cols, eps=, rel=, abs_scale=)``: the joint solve's analytic gradient ``J^T r`` agrees
    with central finite differences of its cost in the columns ``cols``, within
    ``rel`` and ``abs_scale * (1 + |numeric|)``."""
    from core.joint_solve import solver as slv

    def check(prob, x, cols, *, eps, rel, abs_scale):
        _, r, jac = slv.residuals(prob, x)
        grad = jac.T @ r
        for c in cols:
            xp, xm = x.copy(), x.copy()
            xp[c] += eps
            xm[c] -= eps
            num = (slv.residuals(prob, xp, False) - slv.residuals(prob, xm, False)) / (2 * eps)
            assert num == pytest.approx(grad[c], rel=rel, abs=abs_scale * (1 + abs(num)))

    return check


@pytest.fixture(scope="module")
def networks():
    """BlazePose's two networks, loaded once per test module; the detector must be installed."""
    from core.pose_detection import runtime

    ok, why = runtime.available()
    if not ok:
        pytest.fail(f"the detector must be installed for the tests (make models does it): {why}")
    return runtime.Networks(threads=2)
