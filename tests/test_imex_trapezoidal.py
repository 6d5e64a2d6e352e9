"""The ``imex_trapezoidal`` scheme (kernels/implicit_stretching.py, docs/model.md §9.5.1):
the stretching by the trapezoidal rule (Newmark's average acceleration), the rest
symplectic Euler. Against the explicit scheme's fine solution: with a hysteretic law
without return-point memory it keeps a tenth of imex's floor, because it does not damp the
stretching vibrations the explicit solution carries."""

import numpy as np
import pytest
from conftest import overrides

import warpcloth as wc

PROBE_INTERVAL = 1.0 / 600.0  # both bundled scenes; a dt that divides it puts every probe on its time


def run(scene, scheme, dt, **fields):
    return wc.simulate(wc.load_scene(scene, overrides(integrator__scheme=scheme, integrator__dt_s=dt, **fields)))


def tip_error(result, reference):
    tip = reference.probe("tip_x", 0)
    return np.abs(result.probe("tip_x", 0) - tip).max() / np.ptp(tip)


@pytest.mark.slow
def test_the_papers_law_keeps_a_tenth_of_imexs_floor():
    # the paper's law (no return-point memory) integrates the total variation of the
    # stretching vibrations: backward Euler damps them, the explicit solution and the
    # trapezoidal rule do not. Measured over 1 s of the swing against dt = 2e-6 s:
    # imex 0.51 % at 1/16 of the probe interval and 0.78 % at 1/4; imex_trapezoidal
    # 0.043 % and 0.077 %
    paper = {"material__bending_law": "tagawa2003", "run__duration_s": 1.0}
    reference = run("damped_swing", "semi_implicit", 2e-6, **paper)
    trapezoidal = {
        k: tip_error(run("damped_swing", "imex_trapezoidal", PROBE_INTERVAL / k, **paper), reference) for k in (16, 4)
    }
    backward = tip_error(run("damped_swing", "imex", PROBE_INTERVAL / 4, **paper), reference)
    print({k: f"{e:.4%}" for k, e in trapezoidal.items()}, f"imex {backward:.4%}")
    assert trapezoidal[16] < 8e-4 and trapezoidal[4] < 1.5e-3
    assert backward > 5 * trapezoidal[4]


@pytest.mark.slow
def test_the_driven_clamp_enters_the_trapezoidal_solve():
    # the impulsive rotation (h = 2.5 mm): the clamp-edge node's displacement over the step
    # before enters the right-hand side. masing, 1/8 of the probe interval, against
    # dt = 2e-6 s: measured 0.015 % (imex: 0.070 %)
    masing = {"material__bending_law": "masing"}
    reference = run("impulsive_rotation", "semi_implicit", 2e-6, **masing)
    trapezoidal = tip_error(run("impulsive_rotation", "imex_trapezoidal", PROBE_INTERVAL / 8, **masing), reference)
    backward = tip_error(run("impulsive_rotation", "imex", PROBE_INTERVAL / 8, **masing), reference)
    print(f"imex_trapezoidal {trapezoidal:.4%}, imex {backward:.4%}")
    assert trapezoidal < 3e-4
    assert backward > 3 * trapezoidal


def test_it_converges_to_the_explicit_solution():
    # elastic swing, 1 s through hold and release, against dt = 2e-6 s: measured 0.0049 % at
    # 1/32 of the probe interval and 0.0325 % at 1/8 (order 1.4: the transverse motion's
    # leapfrog near its bending limit, not the stretching, sets it)
    elastic = {"material__hysteresis_d1_gf_cm_per_cm": 0.0, "run__duration_s": 1.0}
    reference = run("damped_swing", "semi_implicit", 2e-6, **elastic)
    errors = {
        k: tip_error(run("damped_swing", "imex_trapezoidal", PROBE_INTERVAL / k, **elastic), reference) for k in (32, 8)
    }
    print({k: f"{e:.4%}" for k, e in errors.items()})
    assert errors[32] < 2e-4 and errors[8] < 1e-3
    assert errors[8] > 4 * errors[32]  # at least first order: it converges
