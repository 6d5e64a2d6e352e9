"""The SI simulation core on its own: a batch built from Python equals one built from
scenes, each scheme has its solver, and the laws' tangents are their derivatives."""

import numpy as np
import pytest
import warp as wp
from conftest import loop_asymptote_of, overrides, paper_loop
from warpcloth.kernels import PROBE_FIELDS, PROBE_INDEX, PROBE_UNITS, bending_tagawa2003, integrators, tensile
from warpcloth.kernels.types import LAW_PARAMETER_SLOTS, precision

import warpcloth as wc
from warpcloth import sim
from warpcloth.scene import rest_positions, to_si
from warpcloth.scene.clamp_motion import clamp_pieces


def test_a_batch_built_in_si_runs_bit_for_bit_like_its_scene():
    # Two strips of the impulsive rotation built by hand (SI numbers, no scene file)
    # against the same two built from scenes: the builder is a real entry, not a shim.
    scenes = [
        wc.load_scene(
            "impulsive_rotation",
            overrides(run__duration_s=0.1, damping__gamma_per_s=g, clamp__rotation_centre_dy_mm=dy),
        )
        for g, dy in ((0.2, 2.8), (0.9, -1.0))
    ]
    expected = wc.simulate(scenes)
    first = scenes[0]
    builder = sim.StripBuilder(rest_positions(first), n_clamped=first.n_clamped, spacing=2.5e-3)
    for scene in scenes:
        centre = 1e-3 * np.array([0.0, scene.clamp.rotation_centre_dy_mm])
        builder.add_strip(
            to_si(scene.material),
            width=0.05,
            damping=scene.damping.gamma_per_s,
            clamp=sim.ClampMotion(*clamp_pieces(scene.clamp)),
            rotation_centre=centre,
        )
    model = builder.finalize(device="cpu")
    solver = sim.SemiImplicitEulerSolver(model, dt=5e-6)
    recorder = sim.Recorder(interval=1 / 600, probes_per_frame=10, duration=0.1, laser_height=-0.08)
    result = sim.simulate_batch(model, model.control(), solver, recorder)
    np.testing.assert_array_equal(result.probes, expected.probes)
    np.testing.assert_array_equal(result.frames, expected.frames)


def chain(n, h=5e-3):
    return np.stack([np.zeros(n), -h * np.arange(n)], axis=-1)


def test_builder_refuses_what_the_kernel_cannot_simulate():
    with pytest.raises(ValueError, match="at least 2 free nodes"):
        sim.StripBuilder(chain(4), n_clamped=3, spacing=5e-3)
    with pytest.raises(ValueError, match=r"segment \d of rest_positions is 0.005 m long, not the spacing 0.001 m"):
        sim.StripBuilder(chain(8), n_clamped=3, spacing=1e-3)
    with pytest.raises(ValueError, match="at least one strip"):
        sim.StripBuilder(chain(8), n_clamped=3, spacing=5e-3).finalize()
    with pytest.raises(ValueError, match="edge_hinge_length: 0 m must lie in"):
        sim.StripBuilder(chain(8), n_clamped=3, spacing=5e-3).add_strip(
            to_si(wc.load_scene("damped_swing").material), width=0.05, edge_hinge_length=0.0
        )
    with pytest.raises(TypeError, match="base of the Euler solvers"):
        builder = sim.StripBuilder(chain(8), n_clamped=3, spacing=5e-3)
        builder.add_strip(to_si(wc.load_scene("damped_swing").material), width=0.05)
        sim.FusedStripSolver(builder.finalize(), dt=1e-5)


def test_a_model_keeps_what_was_built():
    material = to_si(wc.load_scene("damped_swing").material)
    builder = sim.StripBuilder(chain(8), n_clamped=3, spacing=5e-3)
    builder.add_strip(material, width=0.05)
    model = builder.finalize()
    builder.add_strip(material, width=0.03)  # after finalize: a new batch, not this model
    assert model.n_strips == 1 and model.control().rotation_centre.shape == (1, 2)
    assert model.state().struct.position.shape == (8, 1)


def test_each_scheme_has_its_solver_and_they_differ_by_order_dt():
    schemes = {"semi_implicit", "forward", "imex", "imex_trapezoidal"}
    assert set(sim.SOLVERS) == schemes == set(integrators.build(wp.float64).schemes)

    def gap(dt):
        runs = {
            scheme: wc.simulate(
                wc.load_scene(
                    "impulsive_rotation",
                    overrides(run__duration_s=0.002, integrator__scheme=scheme, integrator__dt_s=dt),
                )
            )
            for scheme in ("semi_implicit", "forward")
        }
        return np.nanmax(np.abs(runs["forward"].probe("tip_speed", 0) - runs["semi_implicit"].probe("tip_speed", 0)))

    # two first-order schemes: their difference halves with dt (and is not zero)
    coarse, fine = gap(5e-8), gap(2.5e-8)  # small enough that forward Euler has not yet grown
    assert fine > 0 and 1.7 < coarse / fine < 2.3


@pytest.fixture(scope="module")
def tensile_kernel():
    law = tensile.build(wp.float64)
    vec4 = precision(wp.float64).vec4

    @wp.kernel
    def evaluate(
        strain: wp.array(dtype=wp.float64),
        a: vec4,
        force: wp.array(dtype=wp.float64),
        energy: wp.array(dtype=wp.float64),
        stiffness: wp.array(dtype=wp.float64),
    ):
        i = wp.tid()
        force[i] = law.force_per_width(strain[i], a)
        energy[i] = law.energy_per_width(strain[i], a)
        stiffness[i] = law.stiffness_per_width(strain[i], a)

    return evaluate, vec4


def test_tensile_energy_and_tangent_are_the_integral_and_derivative_of_the_force(tensile_kernel):
    evaluate, vec4 = tensile_kernel
    a = (2000.0, 300.0, 4e4, 2.93e7)  # every power present, so every coefficient is checked
    strain = np.linspace(-0.2, 0.2, 4001)
    out = [wp.zeros(len(strain), dtype=wp.float64) for _ in range(3)]
    wp.launch(evaluate, dim=len(strain), inputs=[wp.array(strain, dtype=wp.float64), vec4(*a), *out])
    force, energy, stiffness = (o.numpy() for o in out)
    # the reference: numpy's own derivative and integral of the quartic, odd-extended
    quartic = np.polynomial.Polynomial([0.0, *a])
    e = np.abs(strain)
    np.testing.assert_allclose(force, np.sign(strain) * quartic(e), rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(stiffness, quartic.deriv()(e), rtol=1e-13)
    np.testing.assert_allclose(energy, quartic.integ()(e), rtol=1e-13, atol=1e-15)
    assert stiffness[len(strain) // 2] == a[0]  # dT/dε at ε = 0 is a1


def test_bending_tangent_is_the_slope_of_the_moment_on_each_branch():
    material = to_si(wc.load_scene("damped_swing").material)
    k0 = material.bending.hysteresis_k0
    # rising to K0, then falling to −K0: one reversal, at the sample where the path turns
    n = 20001
    path = np.concatenate([np.linspace(-0.3 * k0, k0, n), np.linspace(k0, -k0, n)[1:]])
    moment, _, tangent = sim.moment_along_path(material, path, with_tangent=True)
    step = np.diff(path)
    slope = np.diff(moment) / step
    midpoint_tangent = 0.5 * (tangent[1:] + tangent[:-1])
    smooth = np.ones(len(step), dtype=bool)
    smooth[n - 2 : n + 1] = False  # the reversal itself: the branch changes there
    np.testing.assert_allclose(slope[smooth], midpoint_tangent[smooth], rtol=1e-6)
    assert np.all(tangent > material.bending_rigidity)  # the hysteretic part stiffens both branches
    elastic = sim.MaterialSI(material.density, material.tensile, material.bending_rigidity, paper_loop(0.0, 1.0, 1.0))
    _, _, flat = sim.moment_along_path(elastic, path, with_tangent=True)
    assert np.all(flat == material.bending_rigidity)  # D1 = 0: the law is M = D K exactly


def test_every_probe_has_a_slot_and_a_unit():
    assert list(PROBE_INDEX) == list(PROBE_FIELDS) == list(PROBE_UNITS)
    assert sorted(PROBE_INDEX.values()) == list(range(len(PROBE_FIELDS)))


def test_packed_parameters_follow_the_declared_layout():
    m = to_si(wc.load_scene("damped_swing_paper").material)
    packed = m.bending_parameters()
    assert len(packed) == LAW_PARAMETER_SLOTS and packed[-1] == 0.0  # tagawa2003 is law 0 (kernels/laws.py)
    layout = dict(zip(bending_tagawa2003.PACKED, packed, strict=False))
    assert layout == {
        "bending_rigidity": m.bending_rigidity,
        "hysteresis_d1": m.bending.hysteresis_d1,
        "hysteresis_alpha": m.bending.hysteresis_alpha,
        "hysteresis_k0": m.bending.hysteresis_k0,
        "hysteresis_m0": loop_asymptote_of(m),
    }
    b = m.bending
    assert loop_asymptote_of(m) == pytest.approx(
        0.5 * b.hysteresis_d1 * (1 + np.exp(-2 * b.hysteresis_alpha * b.hysteresis_k0)), rel=1e-15
    )
