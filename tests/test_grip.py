"""The clamp's grip (docs/model.md §5.4): over ℓ_g below the clamp edge the bending
rigidity is a factor times the fabric's. Exact reference: the first period of the clamped
hanging beam with a stiff root section, from a shooting solution of the two-section beam
(warpcloth.calibrate.references.two_section_beam_mode), started in its own mode shape."""

import functools
import math

import numpy as np
import pytest
from conftest import overrides
from test_analytic import mode_start
from test_clamp_root import smoothed_period

import warpcloth as wc
from warpcloth.calibrate.references import hanging_beam_eigenvalue, two_section_beam_mode
from warpcloth.scene import to_si
from warpcloth.strip import Grip

LENGTH_M = 0.1
CASES = {  # gravity (m/s²), D (gf·cm²/cm), ℓ_g (mm), factor on D
    "γ = 203, 20 mm × 3": (9.80665, 0.1, 20.0, 3.0),
    "γ = 203, 12.5 mm × 5": (9.80665, 0.1, 12.5, 5.0),
    "γ = 20.3, 20 mm × 3": (9.80665, 1.0, 20.0, 3.0),
    "no gravity, 20 mm × 3": (0.0, 0.1, 20.0, 3.0),
}


def test_the_two_section_reference_has_its_limits():
    # factor 1 is the uniform beam whatever the length; a rigid root of length a leaves the
    # cantilever of length 1 − a: λ = 1.8751² / (1 − a)² (measured to 7e-7, the rigid
    # root's 1e6 being finite). 500 RK4 steps: λ to ~1e-9, and fast.
    uniform = two_section_beam_mode(203.0, steps=500)[0]
    assert two_section_beam_mode(203.0, 0.2, 1.0, steps=500)[0] == pytest.approx(uniform, rel=1e-12)
    assert two_section_beam_mode(0.0, 0.2, 1e6, steps=500)[0] == pytest.approx(1.875104068711961**2 / 0.8**2, rel=2e-6)
    # a stiffer root raises λ, more the longer it is
    lams = [two_section_beam_mode(203.0, a, 3.0, steps=500)[0] for a in (0.05, 0.1, 0.2)]
    assert uniform < lams[0] < lams[1] < lams[2]


def test_grip_factors_of_the_hinges():
    # [0, h/2] for the clamp-edge hinge, [(j − ½)h, (j + ½)h] below: a hinge half in the zone
    # is the series compliance of its halves; outside the zone every factor is exactly 1
    intervals = np.array([[0.0, 2.5], [2.5, 7.5], [7.5, 12.5], [12.5, 17.5]]) * 1e-3
    factors = Grip(10.0e-3, 3.0, 2.0).hinge_factors(intervals)
    assert factors[:, 0] == pytest.approx([3.0, 3.0, 3.0 / (0.5 + 0.5 * 3.0), 1.0])
    assert factors[:, 1] == pytest.approx([2.0, 2.0, 1.5, 1.0])
    assert np.all(factors[3] == 1.0) and np.all(Grip(10.0e-3).hinge_factors(intervals) == 1.0)


@functools.cache
def reference(gamma, root_length, factor):
    """λ and mode shape with the grip, and λ without it (both spacings share them)."""
    return (*two_section_beam_mode(gamma, root_length, factor), hanging_beam_eigenvalue(gamma))


def periods(spacing_mm, cases):
    """name → (simulated / exact period − 1, exact period with the grip / without − 1)."""
    out = {}
    gravity = {CASES[name][0] for name in cases}
    assert len(gravity) == 1  # gravity is one per batch
    scenes, starts, exact, plain = [], [], [], []
    for name in cases:
        g, rigidity, grip_mm, factor = CASES[name]
        scene = wc.load_scene(
            "damped_swing",
            overrides(
                strip__spacing_mm=spacing_mm,
                material__hysteresis_d1_gf_cm_per_cm=0.0,
                material__bending_rigidity_gf_cm2_per_cm=rigidity,
                damping__gamma_per_s=0.0,
                release__enabled=False,
                run__duration_s=3.6 if g == 0.0 else 0.7,
                run__gravity_m_per_s2=g,
                integrator__dt_s=4e-6 * spacing_mm,
                clamp__grip_length_mm=grip_mm,
                clamp__grip_bending_factor=factor,
            ),
        )
        material = to_si(scene.material)
        gamma = material.density * g * LENGTH_M**3 / material.bending_rigidity
        lam, shape, uniform = reference(gamma, grip_mm * 1e-3 / LENGTH_M, factor)
        scenes.append(scene)
        starts.append(mode_start(scene, lambda s, f=shape: f(s / LENGTH_M) * (s > 0), 1e-3)[:, 0])
        scale = math.sqrt(material.bending_rigidity / (material.density * LENGTH_M**4))
        exact.append(2 * math.pi / (lam * scale))
        plain.append(uniform / lam - 1)
    result = wc.simulate(scenes, initial_positions=np.stack(starts, axis=1))
    for j, name in enumerate(cases):
        out[name] = (smoothed_period(result.t, result.probe("tip_x", j)) / exact[j] - 1, plain[j])
        print(
            f"{name}, h = {spacing_mm} mm: period error {out[name][0]:+.3%} (the grip shortens it by "
            f"{-out[name][1]:.2%})"
        )
    return out


@pytest.fixture(scope="module")
def with_gravity():
    names = [n for n in CASES if CASES[n][0] > 0]
    return periods(5.0, names), periods(2.5, names)


@pytest.mark.slow
def test_a_stiff_grip_zone_gives_the_two_section_beam_period_at_5_mm(with_gravity):
    # Measured at h = 5 mm (2.5 mm): +0.260 % (+0.067 %), +0.112 % (+0.065 %), +0.213 %
    # (+0.056 %), where the grip itself moves the period by 3.3 %, 4.0 % and 10.2 %:
    # second order like the uniform beam (tests/test_clamp_root.py); the hinge the zone's
    # end cuts takes the series compliance of its two parts.
    coarse, fine = with_gravity
    for error, effect in coarse.values():
        assert 0 < error < 0.005
        assert error < abs(effect) / 10
    for name in ("γ = 203, 20 mm × 3", "γ = 20.3, 20 mm × 3"):  # the zone's end on a hinge at both h
        assert math.log2(coarse[name][0] / fine[name][0]) > 1.8


def test_a_stiff_grip_zone_without_gravity():
    # The clamped-free beam with a stiff root: measured +0.233 % at h = 5 mm, where the
    # grip shortens the period by 22 %.
    ((error, effect),) = periods(5.0, ["no gravity, 20 mm × 3"]).values()
    assert 0 < error < 0.005 and error < abs(effect) / 50
