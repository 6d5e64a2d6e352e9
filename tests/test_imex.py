"""The ``imex`` scheme (kernels/implicit_stretching.py, docs/model.md §9.5): stretching by
linearised backward Euler, the rest symplectic Euler. Against the explicit scheme's fine
solution, on the paper's two scenes without hysteresis (with it, the fast stretching
content the implicit step removes moves where the paper's loops close: §9.5 measures
that floor)."""

import numpy as np
import pandas as pd
import pytest
from conftest import overrides

import warpcloth as wc
from warpcloth.errors import DivergenceError

ELASTIC = {"material__hysteresis_d1_gf_cm_per_cm": 0.0}


def run(scene, scheme, dt, **fields):
    return wc.simulate(wc.load_scene(scene, overrides(integrator__scheme=scheme, integrator__dt_s=dt, **fields)))


def tip_error(result, reference):
    tip = reference.probe("tip_x", 0)
    return np.abs(result.probe("tip_x", 0) - tip).max() / np.ptp(tip)


@pytest.fixture(scope="module")
def swing_reference():
    return run("damped_swing", "semi_implicit", 2e-6, run__duration_s=1.0, **ELASTIC)


def test_imex_converges_to_the_explicit_solution_at_first_order(swing_reference):
    # measured (1 s, h = 5 mm, through hold and release): 0.017 % at 5e-5 s (as explicit),
    # 0.088 % at 2e-4, 0.436 % at 8e-4 s, where explicit Euler is unstable beyond 5e-5. These
    # steps do not divide the probe interval: each probe is up to dt/2 off its time, part of
    # the first order here (tests/test_imex_trapezoidal.py uses steps that divide it)
    errors = {
        dt: tip_error(run("damped_swing", "imex", dt, run__duration_s=1.0, **ELASTIC), swing_reference)
        for dt in (5e-5, 2e-4, 8e-4)
    }
    print({f"{dt:g}": f"{e:.3%}" for dt, e in errors.items()})
    order = np.log(errors[8e-4] / errors[2e-4]) / np.log(4)
    assert 0.8 < order < 1.2
    assert errors[5e-5] < 5e-4 and errors[8e-4] < 8e-3
    explicit = tip_error(run("damped_swing", "semi_implicit", 5e-5, run__duration_s=1.0, **ELASTIC), swing_reference)
    assert errors[5e-5] == pytest.approx(explicit, rel=0.2)  # at the explicit limit the two agree


def test_imex_runs_where_explicit_euler_cannot():
    # 2e-4 s is 3.9x the explicit stretching limit (5.09e-5 s): refused before the run for
    # semi_implicit (tests/test_stability.py shows the bound is real), run by imex
    with pytest.raises(wc.SceneError, match="above the semi_implicit scheme's stability limit 5.090e-05 s"):
        run("damped_swing", "semi_implicit", 2e-4, run__duration_s=0.3, **ELASTIC)
    result = run("damped_swing", "imex", 2e-4, run__duration_s=0.3, **ELASTIC)
    assert not result.diverged


def test_imex_removes_almost_no_energy_from_the_swing(swing_reference):
    # undamped elastic swing: the budget's drift over 1 s (two periods) is what the
    # implicit step removes, a few 1e-4 of the peak kinetic energy at 2e-4 s; the swing's
    # amplitude is not visibly damped
    elastic = run("damped_swing", "imex", 2e-4, run__duration_s=1.0, damping__gamma_per_s=0.0, **ELASTIC)
    total = elastic.energy_total()[:, 0]
    peak = elastic.probe("kinetic", 0).max()
    drift = (total[-1] - total[0]) / peak
    print(f"budget change over 1 s at dt = 2e-4: {drift:+.2e} of the peak kinetic energy")
    assert abs(drift) < 5e-4
    explicit = run("damped_swing", "semi_implicit", 2e-6, run__duration_s=1.0, damping__gamma_per_s=0.0, **ELASTIC)
    late = explicit.t > 0.75
    assert np.ptp(elastic.probe("tip_x", 0)[late]) == pytest.approx(np.ptp(explicit.probe("tip_x", 0)[late]), rel=5e-3)


def test_imex_follows_the_driven_clamp():
    # the impulsive rotation: the clamp-edge node's prescribed motion enters the solve;
    # measured 0.041 % at 5e-5 s (explicit is unstable there), 0.14 % at 2e-4 s
    reference = run("impulsive_rotation", "semi_implicit", 2e-6, **ELASTIC)
    result = run("impulsive_rotation", "imex", 5e-5, **ELASTIC)
    assert tip_error(result, reference) < 1e-3
    total = result.energy_total()[:, 0]
    assert np.abs(total - total[0]).max() < 1e-2 * result.probe("kinetic", 0).max()


@pytest.mark.parametrize("scheme", ["imex", "imex_trapezoidal"])
def test_imex_reports_divergence_with_its_own_advice(scheme):
    # with stretching implicit, explicit bending limits dt (∝ h²): 2.5 mm at 1e-3 s
    with pytest.raises(
        DivergenceError, match=rf"try a smaller integrator.dt_s .*with {scheme}, explicit bending limits"
    ):
        run("damped_swing", scheme, 1e-3, strip__spacing_mm=2.5, run__duration_s=0.3)


@pytest.mark.parametrize("scheme", ["imex", "imex_trapezoidal"])
def test_imex_batches_are_independent_bitwise(scheme):
    scenes = [
        wc.load_scene(
            "damped_swing",
            overrides(
                integrator__scheme=scheme,
                integrator__dt_s=1e-4,
                run__duration_s=0.4,
                damping__gamma_per_s=g,
                material__hysteresis_d1_gf_cm_per_cm=d1,
            ),
        )
        for g, d1 in ((0.2, 0.0), (0.6, 0.04), (1.0, 0.08))
    ]
    together = wc.simulate(scenes)
    for j, scene in enumerate(scenes):
        alone = wc.simulate(scene)
        assert np.array_equal(together.probes[..., j], alone.probes[..., 0], equal_nan=True)
        assert np.array_equal(together.frames[:, j], alone.frames[:, 0])


def test_imex_sweeps_are_independent_of_the_thread_count(tmp_path):
    from warpcloth.scene import read_scene_file

    base = read_scene_file("damped_swing")
    base["run"]["duration_s"] = 0.3
    base["integrator"] |= {"scheme": "imex", "dt_s": 1e-4}
    sweep = wc.expand(base | {"sweep": {"grid": {"damping.gamma_per_s": [0.2, 0.5, 0.8, 1.1]}}})
    for threads in (0, 2):
        wc.run_sweep(sweep, tmp_path / f"t{threads}", max_batch=1, workers=threads)
    for name in ("summary.parquet", "probes"):
        a, b = (pd.read_parquet(tmp_path / f"t{t}" / name) for t in (0, 2))
        if "t" in a:
            a, b = (x.sort_values(["variant", "t"]).reset_index(drop=True) for x in (a, b))
        pd.testing.assert_frame_equal(a, b, check_exact=True)


def test_an_unstable_step_whose_segments_keep_their_length_is_reported_not_measured():
    # beyond its bending limit imex grows a zig-zag that no strain check sees (the
    # stretching is implicit); the energy budget stops closing, and the run says so
    # instead of printing a period (docs/model.md §11)
    with pytest.raises(DivergenceError, match=r"strip 0 diverged after t = 0.*energy budget residual.*unstable"):
        run("damped_swing", "imex", 1.6e-3, run__duration_s=0.5)
    stable = run("damped_swing", "imex", 8e-4, run__duration_s=0.5)
    assert not stable.diverged


def test_energy_the_implicit_step_removes_is_not_taken_for_an_instability():
    # a long strip started unstretched (no hold to settle it) and a soft fabric on the
    # driven clamp: backward Euler damps their stretching transients, a budget *loss* of
    # about the strain energy; only energy an unstable step creates stops a strip
    long = run("damped_swing", "imex", 4e-4, strip__free_length_mm=1000.0, release__enabled=False, run__duration_s=0.6)
    assert not long.diverged
    total = long.energy_total()[:, 0]
    assert total[-1] < total[0]  # it did lose energy: the stretching transient, damped
    soft = run("impulsive_rotation", "imex", 2e-4, material__tensile_gf_per_cm=[300.0, 0.0, 0.0, 2.93e7])
    assert not soft.diverged
