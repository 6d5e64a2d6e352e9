"""The continuum limit of motion fits (warpcloth.calibrate.motion_fit.continuum).

The references are not made at the fit's spacing: an analytic model whose residuals carry
a known C·h^p error (the extrapolation must remove it exactly), and the bundled records,
made by runs at 0.625 mm with known truths (scenes/data/make_motion_examples.py; each
header says how little halving that spacing moves it; the rotation's is fitted by the
command in tests/test_fit.py, the sheet's, at 1.25 mm, in tests/test_sheet_fit.py, the
documented path's in tests/test_calibration_path.py). Fitted at the scenes' spacings, each must find the truth
within 2 σ_total, and end ``converged``; a law with no continuum ends ``mesh_dependent``;
levels that disagree with the law's order refine, then refuse.
"""

import copy
import json
import math

import numpy as np
import pytest
from conftest import run_cli

import warpcloth as wc
from warpcloth.calibrate.motion_fit import continuum_limit, fit_motion, free_parameters
from warpcloth.calibrate.motion_fit.continuum import ORDER_TOLERANCE, observed_order
from warpcloth.calibrate.motion_fit.objective import FitObjective
from warpcloth.calibrate.motion_fit.parameters import FreeParameter
from warpcloth.calibrate.motion_fit.verdict import ended_at_bound
from warpcloth.io.measured import read_measurement
from warpcloth.scene import read_scene_file, set_field


class LinearMesh(FitObjective):
    """Residuals r_h(u) = A u − b + C h^p (+ D h^(p+1)): a model whose continuum optimum is
    the least-squares solution of A u = b, and whose mesh error is known exactly."""

    spacing_fields = ("strip.spacing_mm",)

    def __init__(self, h: float, order: float, higher: float = 0.0, bounds: tuple = (-10.0, 10.0)) -> None:
        rng = np.random.default_rng(3)
        self.a = rng.normal(size=(40, 2))
        self.b = rng.normal(size=40)
        self.c = rng.normal(size=40)
        self.h, self.order, self.higher, self.bounds = h, order, higher, bounds
        self.free = [FreeParameter("x", "x", *bounds, 0.0), FreeParameter("y", "y", -10.0, 10.0, 0.0)]
        self.align = 0.0
        self.launches = self.variants = 0

    dt_s = math.nan

    def spacing_of(self, name: str) -> float:
        return self.h

    def refined(self, factor: float) -> "LinearMesh":
        return LinearMesh(self.h * factor, self.order, self.higher, self.bounds)

    def run(self, points: np.ndarray) -> np.ndarray:
        return points

    def residuals(self, result, j, shift, penalise=True):
        x = np.array([p.lower + (p.upper - p.lower) * u for p, u in zip(self.free, result[j], strict=True)])
        return self.a @ x - self.b + self.c * (self.h**self.order + self.higher * self.h ** (self.order + 1))

    def jacobian_u(self) -> np.ndarray:
        return self.a * self.ranges

    def optimum(self) -> np.ndarray:
        return np.linalg.lstsq(self.jacobian_u(), -self.residuals(np.zeros((1, 2)), 0, 0.0), rcond=None)[0]


def fitted_at(objective: LinearMesh) -> tuple[np.ndarray, np.ndarray]:
    u = objective.optimum()
    return u, objective.residuals(u[None], 0, 0.0)


def test_the_extrapolation_removes_a_known_mesh_error_exactly():
    coarse = LinearMesh(h=2.0, order=2.0)
    u, r = fitted_at(coarse)
    truth = np.linalg.lstsq(coarse.a, coarse.b, rcond=None)[0]
    values = np.array(list(coarse.values(u).values()))
    assert np.abs(values - truth).max() > 0.05  # the mesh moves the fit at h = 2
    noise = np.full(2, 1e-4)
    estimate = continuum_limit(coarse, u, coarse.jacobian_u(), r, noise, order=2.0)
    assert estimate.status == "extrapolated" and estimate.pair_mm == (2.0, 1.0)
    assert estimate.observed_orders[0]["order"] == pytest.approx(2.0, abs=1e-9)
    extrapolated = np.array(list(coarse.values(estimate.q).values()))
    np.testing.assert_allclose(extrapolated, truth, atol=1e-9)
    # σ_mesh is the correction from the finest level: a third of the move h → h/2 at p = 2
    fine_fit = np.array(list(LinearMesh(1.0, 2.0).values(fitted_at(LinearMesh(1.0, 2.0))[0]).values()))
    np.testing.assert_allclose(estimate.sigma_mesh, np.abs(fine_fit - truth), rtol=1e-6)


def test_levels_that_disagree_with_the_laws_order_refine_then_refuse():
    # A first-order error where the law promises the second: the three levels say 1, the
    # ladder refines once (h, h/2, h/4: still 1) and no value is extrapolated.
    model = LinearMesh(h=2.0, order=1.0)
    u, r = fitted_at(model)
    estimate = continuum_limit(model, u, model.jacobian_u(), r, np.full(2, 1e-4), order=2.0)
    assert estimate.status == "unresolved" and estimate.q is None
    assert [o["levels_mm"] for o in estimate.observed_orders] == [[4.0, 2.0, 1.0], [2.0, 1.0, 0.5]]
    assert all(o["order"] == pytest.approx(1.0) for o in estimate.observed_orders)
    assert "not the law's 2" in estimate.note and "fit at a finer spacing" in estimate.note
    # a higher-order term that spoils the coarsest level only: the ladder's second rung passes
    model = LinearMesh(h=2.0, order=2.0, higher=0.5)
    u, r = fitted_at(model)
    estimate = continuum_limit(model, u, model.jacobian_u(), r, np.full(2, 1e-4), order=2.0)
    first, second = (o["order"] for o in estimate.observed_orders)
    assert abs(first - 2) > ORDER_TOLERANCE >= abs(second - 2)
    assert estimate.status == "extrapolated" and estimate.pair_mm == (1.0, 0.5)


def test_a_first_order_law_is_extrapolated_at_its_order():
    # the paper's clamp edge: first order, and the law says so; the extrapolation is exact
    model = LinearMesh(h=2.0, order=1.0)
    u, r = fitted_at(model)
    estimate = continuum_limit(model, u, model.jacobian_u(), r, np.full(2, 1e-4), order=1.0)
    assert estimate.status == "extrapolated" and estimate.pair_mm == (2.0, 1.0)
    truth = np.linalg.lstsq(model.a, model.b, rcond=None)[0]
    np.testing.assert_allclose(list(model.values(estimate.q).values()), truth, atol=1e-9)


def test_a_continuum_optimum_beyond_the_box_ends_on_its_bound():
    # bounds that hold the fit at h but not its continuum limit: the estimate stops on the
    # bound (the fit then says at_bound), not in a loop that never settles
    wide = LinearMesh(h=2.0, order=2.0)
    truth = np.linalg.lstsq(wide.a, wide.b, rcond=None)[0]
    at_h = np.array(list(wide.values(fitted_at(wide)[0]).values()))
    edge = float(at_h[0] + 0.3 * (truth[0] - at_h[0]))  # a third of the way from the fit at h to the limit
    bounds = (edge, 10.0) if truth[0] < at_h[0] else (-10.0, edge)
    model = LinearMesh(h=2.0, order=2.0, bounds=bounds)
    u, r = fitted_at(model)
    estimate = continuum_limit(model, u, model.jacobian_u(), r, np.full(2, 1e-4), order=2.0)
    assert estimate.status == "extrapolated"
    assert ended_at_bound(model.free, estimate.q) == ["x"]


def test_observed_order_of_levels_that_agree_to_round_off_is_infinite():
    r = np.linspace(0, 1, 10)
    assert observed_order(r + 4e-3, r + 1e-3, r) == pytest.approx(math.log2(3))
    assert observed_order(r + 1e-3, r, r) == math.inf


def fit_bundled(name, measured, free, fields=(), **options):
    base = read_scene_file(name)
    for key, value in fields:
        set_field(base, key, value)
    scene = wc.scene_from_dict(copy.deepcopy(base))
    measurement = read_measurement(measured)
    return fit_motion(
        base, measurement, free_parameters(free, scene, options.pop("bounds", None)), progress=False, **options
    )


def within(fit, truth: dict) -> None:
    for name, value in truth.items():
        error = fit.parameters[name] - value
        print(
            f"{name}: {fit.parameters[name]:.5g} ± {fit.sigma[name]:.2g} (noise {fit.sigma_noise[name]:.2g}, "
            f"mesh {fit.sigma_mesh[name]:.2g}); at the spacing {fit.at_spacing[name]:.5g}; truth {value:g}; "
            f"{error / fit.sigma[name]:+.2f} σ_total"
        )
        assert abs(error) <= 2 * fit.sigma[name]
        assert fit.sigma[name] == pytest.approx(math.hypot(fit.sigma_noise[name], fit.sigma_mesh[name]))


@pytest.mark.slow
def test_the_swing_fitted_at_5mm_finds_the_continuums_truth():
    # The laser trace of a 0.625 mm run (γ 0.55, D1 0.025, σ 0.2 mm) fitted at the scene's
    # 5 mm: at that spacing alone D1 is ~20 % (dozens of σ_noise) off; extrapolated it is
    # within 2 σ_total.
    truth = {"damping.gamma_per_s": 0.55, "material.hysteresis_d1_gf_cm_per_cm": 0.025}
    fit = fit_bundled(
        "damped_swing",
        "damped_swing_laser",
        "gamma,D1",
        [("integrator.scheme", "imex"), ("integrator.dt_s", "auto")],
    )
    assert fit.status == "converged", fit.problems
    within(fit, truth)
    d1 = "material.hysteresis_d1_gf_cm_per_cm"
    assert abs(fit.at_spacing[d1] - truth[d1]) > 5 * fit.sigma_noise[d1]  # the mesh's error is real
    assert fit.continuum["levels_mm"][:3] == [10.0, 5.0, 2.5]


@pytest.mark.slow
def test_a_fit_under_a_law_without_a_continuum_is_not_converged(tmp_path):
    done = run_cli(
        "fit",
        "damped_swing_paper",
        "--measured",
        "damped_swing_laser",
        "--free",
        "gamma,D1",
        "--set",
        "run.duration_s=1.0",
        "--noise",
        "0.5",  # the paper's law does not explain masing's record to 0.2 mm: what is judged here is the law
        "--out",
        "fit",
        "--no-progress",
        cwd=tmp_path,
    )
    assert done.returncode == 10, done.stderr
    assert "status: mesh_dependent" in done.stdout
    assert "the tagawa2003 law's hysteresis depends on the mesh" in done.stderr
    assert "these are not fabric properties" in done.stderr
    result = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert result["status"] == "mesh_dependent" and result["continuum"] == {}


@pytest.mark.slow
def test_a_swing_fitted_too_coarse_for_its_order_refines_then_refuses():
    # The bundled swing at 10 mm: its motion at 20, 10, 5 mm converges at order 0.8 and at
    # 10, 5, 2.5 mm at 1.45, outside masing's 2 ± 0.5 (measured), so no value is
    # extrapolated and the fit is not converged, whatever its RMS says.
    fit = fit_bundled(
        "damped_swing",
        "damped_swing_laser",
        "gamma,D1",
        [("integrator.scheme", "imex"), ("integrator.dt_s", "auto"), ("strip.spacing_mm", 10.0)],
    )
    c = fit.continuum
    assert c["status"] == "unresolved" and fit.status != "converged"
    assert [o["levels_mm"] for o in c["observed_orders"]] == [[20.0, 10.0, 5.0], [10.0, 5.0, 2.5]]
    assert all(abs(o["order"] - 2) > ORDER_TOLERANCE for o in c["observed_orders"])
    assert any(p.startswith("no continuum estimate: the simulated motion converges at order") for p in fit.problems)
    assert fit.sigma_mesh == {} and fit.parameters == fit.at_spacing  # the values stay the mesh's, and say so


def test_the_old_spacing_check_is_refused_in_one_line_saying_what_replaced_it(tmp_path):
    args = ("damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--check-spacing")
    done = run_cli("fit", *args, "--out", "fit", cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines() == [
        "warpcloth fit: error in option: --check-spacing: is gone: every fit now runs its best point at 2h and "
        "h/2 and reports the values extrapolated to h → 0, the mesh's share in σ (--at-spacing skips that)"
    ]
    assert not (tmp_path / "fit").exists()
