"""The masing_growing law (kernels/bending_masing_growing.py, docs/model.md §4.11): Masing's
rules with a friction that grows with the distance from the fresh state, for woven fabrics'
shear loops, which widen toward their turning point. Its properties, each against a
reference nobody here wrote the law for: a discrete Iwan model whose sliders' friction
grows (scenes/data/make_kes_examples.py, NumPy), return-point memory and continuity in the
path, no energy made on any closed cycle, and masing when the growth is off."""

import numpy as np
import pytest
from test_bending_laws import kes_path, material, wandering_path
from test_masing import EXAMPLES, hysteretic, rippled

PER_CM = 100.0


def growing(beta_cm, **fields):
    return material("masing_growing", hysteresis_growth_cm=beta_cm, **fields)


def test_without_growth_it_is_masing():
    path = 8.0 * wandering_path(1)
    masing, flat = material("masing"), growing(0.0)
    scale = masing.bending.hysteresis_d1
    assert np.abs(hysteretic(flat, path) - hysteretic(masing, path)).max() < 1e-12 * scale


@pytest.mark.parametrize("beta_cm", [0.5, 2.0])
def test_against_an_iwan_model_whose_friction_grows(beta_cm):
    # the law is the continuum limit of Jenkins elements whose sliders' friction grows by
    # √(1 + (β ΔK)²): the difference falls as 1/N with the number of elements, on a path
    # whose loops nest many levels deep (2000 reversals)
    law = growing(beta_cm)
    path = 8.0 * wandering_path(3)
    h = hysteretic(law, path)
    b = law.bending
    errors = [
        np.abs(h - EXAMPLES.iwan_moment(path, b.hysteresis_d1, b.hysteresis_alpha, n, b.hysteresis_growth)).max()
        / np.abs(h).max()
        for n in (1024, 4096)
    ]
    print(f"β = {beta_cm} /cm: masing_growing vs Iwan {errors[0]:.2e}, {errors[1]:.2e} at 1024, 4096 elements")
    assert errors[1] < 2e-4
    assert errors[0] / errors[1] > 3.5


def test_the_moment_is_continuous_in_the_path_and_loops_close_where_they_began():
    # N ripples of ε = 0.01 1/m inserted on a KES cycle move H by O(ε) whatever N (sup-norm
    # continuity; return-point memory closes each ripple where it began)
    law = growing(1.0)
    at = 6000
    reference = hysteretic(law, kes_path())
    changes = []
    for n in (10, 1000):
        path, _ = rippled(at, n, 0.01)
        changes.append(np.abs(hysteretic(law, path)[at + 1 + 8 * n :] - reference[at + 1 :]).max())
    assert max(changes) < 1e-12 * law.bending.hysteresis_d1
    # the major loop is closed from the first cycle on
    k0 = kes_path().max()
    cycle = np.concatenate([np.linspace(k0, -k0, 4001)[1:], np.linspace(-k0, k0, 4001)[1:]])
    h = hysteretic(law, np.concatenate([np.linspace(0.0, k0, 2001), cycle, cycle]))
    first, second = h[2001 : 2001 + len(cycle)], h[2001 + len(cycle) :]
    assert np.abs(first - second).max() < 1e-13 * law.bending.hysteresis_d1


@pytest.mark.parametrize("seed", range(6))
def test_no_closed_cycle_makes_energy(seed):
    # after a random history, any closed excursion K_a → K_b → K_a (nested cycles inside it
    # too) takes work ∮ H dK ≥ 0 (trapezoidal, on a fine path)
    rng = np.random.default_rng(seed)
    law = growing(rng.uniform(0.2, 3.0))
    history = 4.0 * wandering_path(seed, 300)
    start = history[-1]
    knots = [start, *(start + rng.uniform(-400.0, 400.0, 5)), start]
    legs = [np.linspace(a, b, 400, endpoint=False) for a, b in zip(knots[:-1], knots[1:], strict=True)]
    cycle = np.concatenate([*legs, [start]])
    h = hysteretic(law, np.concatenate([history, cycle[1:]]))[len(history) - 1 :]
    work = np.sum(0.5 * (h[1:] + h[:-1]) * np.diff(cycle))
    print(f"seed {seed}: ∮ H dK = {work:.4g} N (β {law.bending.hysteresis_growth:.3g} m)")
    assert work >= -1e-9 * law.bending.hysteresis_d1 * np.ptp(cycle)


def kes_widths(law, k0=8.0, at=(0.5, 5.0)):
    """The loop's width (hysteresis, units of D1's) at ±each of ``at`` (units of K0's scale)
    on the second ±k0 cycle, as KES-FB reads 2HG (0.5) and 2HG5 (5) on a ±8 cycle."""
    k0 = k0 * PER_CM / 8.0 * 2.5
    scale = k0 / 8.0
    up = np.linspace(-k0, k0, 8001)
    path = np.concatenate([np.linspace(0, k0, 4001), up[::-1][1:], up[1:], up[::-1][1:], up[1:]])
    h = hysteretic(law, path)
    rising, falling = h[-8000:], h[-16000:-8000][::-1]
    grid = up[1:]

    def width(x):
        return np.mean([np.interp(v, grid, rising) - np.interp(v, grid, falling) for v in (x * scale, -x * scale)])

    return [width(x) for x in at]


def test_the_loop_widens_toward_the_turning_point_only_with_growth():
    # masing's loop is widest at 0 (2HG5 ≤ 2HG); growth makes it widen outward, more so as β grows
    ratios = []
    for beta in (0.0, 0.3, 1.0, 3.0):
        near, far = kes_widths(growing(beta))
        ratios.append(far / near)
    print("2HG5/2HG-like ratios:", [f"{r:.3f}" for r in ratios])
    assert ratios[0] <= 1.0 and ratios[1] > ratios[0]
    assert np.all(np.diff(ratios) > 0) and ratios[-1] > 1.4
