"""Convergence of the damped swing in dt and in h (observed orders stated)."""

import math

import numpy as np
from conftest import overrides

import warpcloth as wc


def tip_x(**fields):
    scene = wc.load_scene("damped_swing", overrides(run__duration_s=1.0, **fields))
    return wc.simulate(scene).probe("tip_x", 0)


def observed_order(coarse, medium, fine, ratio=2.0):
    """Order p from three solutions refined by ``ratio``: |c − m| / |m − f| = ratio^p."""
    return math.log(np.max(np.abs(coarse - medium)) / np.max(np.abs(medium - fine)), ratio)


def test_time_step_convergence():
    # Semi-implicit Euler is first order: measured p = 2.06, 1.97, 0.99 ratios → p ≈ 1.0.
    runs = {dt: tip_x(integrator__dt_s=dt) for dt in (2e-5, 1e-5, 5e-6, 2.5e-6)}
    p = observed_order(runs[2e-5], runs[1e-5], runs[5e-6])
    print(f"observed order in dt: {p:.2f}")
    assert 0.8 < p < 1.2
    # The scene's default dt (1e-5 s) is accurate: its tip path differs from the
    # Richardson-extrapolated one by 4.6 µm (measured), 1e-4 of the 50 mm swing.
    extrapolated = 2 * runs[2.5e-6] - runs[5e-6]
    assert np.max(np.abs(runs[1e-5] - extrapolated)) < 2e-5


def test_spacing_convergence():
    # Same dt for all (2.5e-6 s, stable at h = 1.25 mm), so only h changes. Measured
    # |Δ| = 2.97 mm (5 → 2.5 mm) and 1.11 mm (2.5 → 1.25 mm): p ≈ 1.4, between the
    # clamp edge's first order (see test_analytic) and the interior's second order.
    runs = {h: tip_x(strip__spacing_mm=h, integrator__dt_s=2.5e-6) for h in (5.0, 2.5, 1.25)}
    p = observed_order(runs[5.0], runs[2.5], runs[1.25])
    print(f"observed order in h: {p:.2f}")
    assert 1.0 < p < 2.2
