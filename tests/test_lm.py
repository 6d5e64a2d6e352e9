"""The motion fit's search algorithm (warpcloth.calibrate.motion_fit.lm) on analytic
least-squares problems with known optima, against SciPy's independent implementations
(scipy.optimize.curve_fit, least_squares): NumPy alone, no Warp, no kernel."""

import subprocess
import sys
from functools import partial
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import curve_fit, least_squares

from warpcloth.calibrate.motion_fit import lm

T = np.linspace(0.0, 3.0, 60)


def decay(t, amplitude, rate):
    return amplitude * np.exp(-rate * t)


def _stencil_jacobian(residuals, rows, pairs):
    # the central differences fit_motion takes from the stencil rows of one batch
    r = [residuals(row) for row in rows]
    return np.column_stack([(r[plus - 1] - r[minus - 1]) / du for plus, minus, du in pairs])


def search(residuals, q0, lower, upper, iterations=200):
    """Drive lm as fit_motion does: each launch evaluates the proposals and the first's stencil."""
    state = lm.start(q0, float(np.mean(residuals(q0) ** 2)), residuals(q0))
    stages = []
    for _ in range(iterations):
        points = lm.proposals(state, lower, upper)
        rows, pairs = lm.stencil(points[0])
        state, stage = lm.step(
            state, points, [residuals(p) for p in points], partial(_stencil_jacobian, residuals, rows, pairs)
        )
        stages.append(stage)
        if state.converged:
            break
    return state, stages


class DecayProblem:
    """y = A exp(−k t) + white noise, fitted in the unit box of [lo, hi]."""

    def __init__(self, lo, hi, truth=(1.3, 1.7), sigma=0.01, seed=4):
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)
        self.y = decay(T, *truth) + np.random.default_rng(seed).normal(0.0, sigma, T.size)

    def values(self, u):
        return self.lo + u[:2] * (self.hi - self.lo)

    def residuals(self, u):
        return decay(T, *self.values(u)) - self.y


def test_it_finds_curve_fits_optimum_and_covariance():
    problem = DecayProblem(lo=(0.5, 0.5), hi=(2.0, 5.0))
    state, stages = search(problem.residuals, np.array([0.2, 0.8]), np.zeros(2), np.ones(2))
    assert state.converged and stages[0] == "step" and len(stages) < 30
    reference, reference_cov = curve_fit(decay, T, problem.y, p0=(1.0, 1.0))
    sigma, correlation = lm.sigma_and_correlation(reference_cov)
    found = problem.values(state.q)
    assert np.all(np.abs(found - reference) < 0.01 * sigma)  # the same optimum, well inside its σ
    jac = state.jac / (problem.hi - problem.lo)  # ∂r/∂(A, k)
    np.testing.assert_allclose(lm.covariance(jac, state.residual), reference_cov, rtol=1e-3)
    assert 0.3 < correlation[0, 1] < 1  # a larger A wants a faster decay: a real correlation, not the identity


def test_it_solves_rosenbrock_in_a_box_like_scipy():
    # r = (10 (x1 − x0²), 1 − x0): the banana valley, optimum (1, 1) with zero cost
    def residuals(u):
        x = -2.0 + 4.0 * u
        return np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])

    state, _ = search(residuals, (np.array([-1.2, 1.0]) + 2.0) / 4.0, np.zeros(2), np.ones(2))
    x = -2.0 + 4.0 * state.q
    np.testing.assert_allclose(x, [1.0, 1.0], atol=1e-6)
    scipy_x = least_squares(lambda x: residuals((x + 2.0) / 4.0), [-1.2, 1.0], method="lm").x
    np.testing.assert_allclose(x, scipy_x, atol=1e-6)


def test_an_optimum_outside_the_box_ends_on_its_bound():
    # k's true 1.7 lies above the box's 1.5: the search stops on the bound, not past it
    problem = DecayProblem(lo=(0.5, 0.5), hi=(2.0, 1.5))
    state, _ = search(problem.residuals, np.array([0.5, 0.5]), np.zeros(2), np.ones(2))
    assert state.q[1] == 1.0 and 0.0 < state.q[0] < 1.0


def test_a_rejected_step_raises_the_damping_until_the_search_stops():
    state = lm.State(np.zeros(1), 0.0, np.zeros(1), np.ones((1, 1)), 1e7)
    state, stage = lm.step(state, [np.ones(1)] * 3, [np.ones(1)] * 3, lambda: pytest.fail("not taken"))
    assert (stage, state.lam, state.converged) == ("rejected", 1e9, True)


def test_a_singular_jacobian_gives_nan_covariance_not_a_number_to_trust():
    assert np.isnan(lm.covariance(np.ones((5, 2)))).all()


def test_the_algorithm_needs_neither_warp_nor_the_rest_of_warpcloth():
    path = Path(lm.__file__)
    code = (
        "import sys, importlib.util; sys.modules['warp'] = None; "
        f"spec = importlib.util.spec_from_file_location('lm', {str(path)!r}); "
        "m = sys.modules['lm'] = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); "
        "assert not [k for k, v in sys.modules.items() if v and k.startswith('warp')]"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
