"""The bending laws (kernels/bending_*.py) on prescribed curvature paths, against
their closed forms, each other where they coincide, a published update form, and in
one batch (docs/model.md §4)."""

import numpy as np
import pytest
from conftest import loop_asymptote_of, overrides

import warpcloth as wc
from warpcloth.scene import to_si
from warpcloth.strip import moment_along_path

GF_CM = 9.80665e-3  # gf·cm/cm → N (units.MOMENT_GF_CM_PER_CM)
PER_CM = 100.0  # 1/cm → 1/m


def material(law, **fields):
    return to_si(
        wc.load_scene(
            "damped_swing", {"material.bending_law": law, **{f"material.{k}": v for k, v in fields.items()}}
        ).material
    )


def kes_path(k0_per_cm=2.5, samples=2000):
    """0 → K0 → −K0 → K0, 1/m (a KES-FB2 cycle)."""
    k0 = k0_per_cm * PER_CM
    return np.concatenate(
        [np.linspace(0, k0, samples), np.linspace(k0, -k0, 2 * samples)[1:], np.linspace(-k0, k0, 2 * samples)[1:]]
    )


def wandering_path(seed=0, n=4000):
    """A curvature history with many reversals of every size, 1/m."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(0, 0.6, n) * (1 + 4 * (rng.random(n) < 0.05))
    return np.cumsum(steps)


def dahl_by_ode(path, m_s, k_s, n, substeps=400):
    """dh/dK = (M_s/K_s)(1 − s h/M_s)^n integrated by RK4 in small steps (an independent
    reference for the closed-form update)."""
    h, out = 0.0, [0.0]
    for a, b in zip(path[:-1], path[1:], strict=True):
        s = np.sign(b - a)
        dk = (b - a) / substeps

        def rate(h, s=s):
            return m_s / k_s * max(1 - s * h / m_s, 0.0) ** n

        for _ in range(substeps):
            r1 = rate(h)
            r2 = rate(h + 0.5 * dk * r1)
            r3 = rate(h + 0.5 * dk * r2)
            r4 = rate(h + dk * r3)
            h += dk * (r1 + 2 * r2 + 2 * r3 + r4) / 6
        out.append(h)
    return np.array(out)


def test_dahl_with_exponent_one_is_the_papers_law():
    # On a branch the paper's offset obeys dh/dK = α (M0 − s h): Dahl with n = 1,
    # M_s = M0, K_s = 1/α; at a reversal both keep h and flip s (docs/model.md §4.8)
    paper = material("tagawa2003")
    dahl = material(
        "dahl",
        dahl_moment_gf_cm_per_cm=loop_asymptote_of(paper) / GF_CM,
        dahl_curvature_per_cm=1 / (paper.bending.hysteresis_alpha * PER_CM),
        dahl_exponent=1.0,
    )
    for path in (kes_path(), wandering_path(1), kes_path()[::97]):
        m, _ = moment_along_path([paper, dahl], path)
        assert np.abs(m[:, 0] - m[:, 1]).max() < 1e-12 * np.abs(m[:, 0]).max()


def test_dahl_against_the_published_exponential_update():
    # Miguel et al. (2013) / NVIDIA Newton's cable: σ ← d σ_max (1 − e^{−d Δκ/τ}) + σ e^{−d Δκ/τ}
    m_s, k_s = 0.03 * GF_CM, 0.3 * PER_CM
    law = material("dahl", dahl_moment_gf_cm_per_cm=0.03, dahl_curvature_per_cm=0.3, dahl_exponent=1.0)
    path = wandering_path(2)
    sigma, expected = 0.0, [0.0]
    for a, b in zip(path[:-1], path[1:], strict=True):
        d = 1.0 if b > a else -1.0
        decay = np.exp(-d * (b - a) / k_s)
        sigma = d * m_s * (1 - decay) + sigma * decay
        expected.append(sigma)
    m, _ = moment_along_path(law, path)
    np.testing.assert_allclose(m - law.bending_rigidity * path, expected, rtol=0, atol=1e-12 * m_s)


@pytest.mark.parametrize("n", [0.5, 2.0, 3.0])
def test_dahl_shape_exponent_against_an_integrated_ode(n):
    law = material("dahl", dahl_moment_gf_cm_per_cm=0.03, dahl_curvature_per_cm=0.4, dahl_exponent=n)
    path = kes_path(samples=60)  # coarse steps: the update is exact, not a time step
    m, _ = moment_along_path(law, path)
    reference = dahl_by_ode(path, law.bending.dahl_moment, law.bending.dahl_curvature, n)
    np.testing.assert_allclose(m - law.bending_rigidity * path, reference, rtol=0, atol=1e-7 * law.bending.dahl_moment)


def legs(nodes, steps):
    """A path through the curvature ``nodes`` (1/m) in ``steps`` equal steps per leg."""
    return np.concatenate(
        [nodes[:1]] + [np.linspace(a, b, steps + 1)[1:] for a, b in zip(nodes[:-1], nodes[1:], strict=True)]
    )


def test_dahl_sampling_does_not_change_the_loop():
    # the update is the exact solution over each monotone step: 20 or 4000 steps per leg
    # give the same moments where the paths meet
    law = material("dahl", dahl_exponent=2.0)
    nodes = np.array([0.0, 250.0, -250.0, 180.0, -60.0, 250.0])
    fine, coarse = legs(nodes, 4000), legs(nodes, 20)
    m_fine, _ = moment_along_path(law, fine)
    m_coarse, _ = moment_along_path(law, coarse)
    np.testing.assert_allclose(coarse, fine[::200], rtol=1e-14, atol=1e-12)
    assert np.abs(m_coarse - m_fine[::200]).max() < 1e-12 * np.abs(m_fine).max()


def test_frictional_couple_loop_branches_width_and_area():
    m_f, k_w = 0.025, 0.1  # gf·cm/cm, 1/cm
    law = material("frictional_couple", friction_moment_gf_cm_per_cm=m_f, friction_width_per_cm=k_w)
    path = kes_path(samples=20000)
    m, work = moment_along_path(law, path)
    h = (m - law.bending_rigidity * path) / GF_CM
    k = path / PER_CM
    falling = np.arange(len(path)) >= 20000 - 1
    falling &= np.arange(len(path)) < 60000 - 2
    rising = np.arange(len(path)) >= 60000 - 2
    # once the spring has taken up 2 K_w after a reversal the couple is ±M_f exactly: the
    # branches are M = D K ± M_f, and 2HB = 2 M_f
    slipping_down = falling & (k < 2.5 - 2 * k_w - 1e-9)
    slipping_up = rising & (k > -2.5 + 2 * k_w + 1e-9)
    np.testing.assert_allclose(h[slipping_down], -m_f, rtol=1e-12)
    np.testing.assert_allclose(h[slipping_up], m_f, rtol=1e-12)
    # within the play it moves with the spring's slope M_f / K_w
    sticking = falling & (k > 2.5 - 2 * k_w + 1e-3)
    np.testing.assert_allclose(np.diff(h[sticking]) / np.diff(k[sticking]), m_f / k_w, rtol=1e-9)
    # the closed cycle K0 → −K0 → K0 is a parallelogram in (K, h): area 4 M_f (K0 − K_w)
    cycle = slice(20000 - 1, None)
    area = np.sum(h[cycle][:-1] * np.diff(k[cycle]))
    assert area == pytest.approx(4 * m_f * (2.5 - k_w), rel=1e-4)


def test_frictional_couple_is_dahls_zero_exponent_limit():
    friction = material("frictional_couple", friction_moment_gf_cm_per_cm=0.02, friction_width_per_cm=0.15)
    dahl = material("dahl", dahl_moment_gf_cm_per_cm=0.02, dahl_curvature_per_cm=0.15, dahl_exponent=0.0)
    path = wandering_path(3)
    m, _ = moment_along_path([friction, dahl], path)
    assert np.abs(m[:, 0] - m[:, 1]).max() < 1e-12 * np.abs(m[:, 0]).max()


@pytest.mark.parametrize(
    "law, field",
    [
        ("tagawa2003", "hysteresis_d1_gf_cm_per_cm"),
        ("dahl", "dahl_moment_gf_cm_per_cm"),
        ("frictional_couple", "friction_moment_gf_cm_per_cm"),
        ("masing", "hysteresis_d1_gf_cm_per_cm"),
    ],
)
def test_each_law_is_elastic_without_its_hysteresis_and_continuous_with_it(law, field):
    path = wandering_path(4)
    elastic = material(law, **{field: 0.0})
    m, _, slope = moment_along_path(elastic, path, with_tangent=True)
    np.testing.assert_array_equal(m, elastic.bending_rigidity * path)
    np.testing.assert_array_equal(slope, elastic.bending_rigidity)
    hysteretic = material(law)
    m, _, slope = moment_along_path(hysteretic, path, with_tangent=True)
    # continuous: no step larger than the steepest branch allows (right after a reversal
    # from saturation: D + 2 α M0, D + 2^n M_s / K_s, D + M_f / K_w, D + α D1)
    b = hysteretic.bending
    steepest = {
        "tagawa2003": lambda: 2 * loop_asymptote_of(hysteretic) / b.hysteresis_alpha**-1,
        "dahl": lambda: 2**b.dahl_exponent * b.dahl_moment / b.dahl_curvature,
        "frictional_couple": lambda: b.friction_moment / b.friction_width,
        "masing": lambda: b.hysteresis_alpha * b.hysteresis_d1,
    }[law]()
    bound = (hysteretic.bending_rigidity + steepest) * np.abs(np.diff(path))
    assert np.all(np.abs(np.diff(m)) <= 1.000001 * bound)
    # the tangent is the slope of the branch being followed
    smooth = np.abs(np.diff(path)) < 0.05
    secant = np.diff(m)[smooth] / np.diff(path)[smooth]
    assert np.median(np.abs(secant - slope[1:][smooth]) / slope.max()) < 0.05


def test_the_laws_run_in_one_batch_as_each_alone():
    laws = ["tagawa2003", "dahl", "frictional_couple", "masing"]
    scenes = [
        wc.load_scene(
            "damped_swing",
            overrides(
                run__duration_s=0.3, material__bending_law=law, material__dahl_exponent=2.0 if law == "dahl" else 1.0
            ),
        )
        for law in laws
    ]
    together = wc.simulate(scenes)
    for j, scene in enumerate(scenes):
        alone = wc.simulate(scene)
        assert np.array_equal(together.probes[..., j], alone.probes[..., 0], equal_nan=True), laws[j]
        assert np.array_equal(together.frames[:, j], alone.frames[:, 0]), laws[j]
    # the default Dahl material is the paper's exactly (n = 1, M_s = M0, K_s = 1/α)
    default_dahl = wc.simulate(
        wc.load_scene("damped_swing", overrides(run__duration_s=0.3, material__bending_law="dahl"))
    )
    assert np.abs(default_dahl.probe("tip_x", 0) - together.probe("tip_x", 0)).max() < 1e-12
    assert together.parameters["material.dahl_exponent"].tolist() == [1.0, 2.0, 1.0, 1.0]


@pytest.mark.parametrize("law", ["dahl", "frictional_couple", "masing"])
def test_the_energy_budget_closes_with_each_law(law):
    # as test_energy.py's hysteretic swing: the sum of every term stays within 0.05 % of
    # the peak kinetic energy, and the law really dissipates
    shape = {"material__dahl_exponent": 0.5} if law == "dahl" else {}
    scene = wc.load_scene(
        "damped_swing",
        overrides(
            run__duration_s=2.0, integrator__dt_s=1e-5, damping__gamma_per_s=0.3, material__bending_law=law, **shape
        ),
    )
    result = wc.simulate(scene)
    total = result.energy_total()[:, 0]
    scale = result.probe("kinetic", 0).max()
    assert np.ptp(total) / scale < 5e-4
    assert result.probe("hysteresis_work", 0)[-1] > 0.1 * scale


def test_a_laws_parameters_are_fitted_only_for_that_law():
    from warpcloth.calibrate.motion_fit import free_parameters
    from warpcloth.errors import ArgumentError

    dahl = wc.load_scene("damped_swing", {"material.bending_law": "dahl"})
    fitted = free_parameters("gamma,Ms,n", dahl)
    assert [p.field for p in fitted] == [
        "damping.gamma_per_s",
        "material.dahl_moment_gf_cm_per_cm",
        "material.dahl_exponent",
    ]
    assert fitted[1].lower == 0.0 and fitted[1].upper == pytest.approx(4 * dahl.material.dahl_moment_gf_cm_per_cm)
    with pytest.raises(
        ArgumentError,
        match=r"names: D1 \(material.hysteresis_d1_gf_cm_per_cm\) is a parameter of "
        r"the tagawa2003 or masing or masing_growing bending law, but the scene's material uses dahl",
    ):
        free_parameters("gamma,D1", dahl)
    with pytest.raises(
        ArgumentError, match="Mf .* frictional_couple bending law, but the scene's material uses masing"
    ):
        free_parameters("Mf", wc.load_scene("damped_swing"))


def test_a_sweep_over_the_law_keeps_the_law_in_every_result(tmp_path):
    from warpcloth.scene import read_scene_file

    base = read_scene_file("damped_swing")
    base["run"]["duration_s"] = 0.1
    sweep = wc.expand(base | {"sweep": {"grid": {"material.bending_law": ["tagawa2003", "dahl", "frictional_couple"]}}})
    wc.run_sweep(sweep, tmp_path / "s", workers=0, frames=True, probes="all", progress=False)
    recording = wc.load_recording(tmp_path / "s")
    assert list(recording.to_xarray()["material.bending_law"].values) == ["tagawa2003", "dahl", "frictional_couple"]
    assert set(recording.to_dataframe()["material.bending_law"]) == {"tagawa2003", "dahl", "frictional_couple"}
    only = wc.load_recording(tmp_path / "s", where="material.bending_law==dahl")
    assert only.variants.tolist() == [1]
    with pytest.raises(wc.ArgumentError, match="where: material.bending_law is a choice .* compare it with == or !="):
        wc.load_recording(tmp_path / "s", where="material.bending_law<dahl")
    out = wc.export_usd(recording, tmp_path / "laws.usda")
    assert 'string[] primvars:warpcloth:material:bending_law = ["dahl"]' in out.read_text()


@pytest.mark.parametrize("offset", [1e-3, 1e-7, 1e-10, 1e-13])
def test_dahl_is_continuous_in_its_exponent_through_one(offset):
    # the update must not cancel as n → 1: n = 1 ± δ differs from n = 1 by O(δ), not by
    # rounding amplified 1/δ times (measured 0.13 M_s at δ = 1e-14 before the fix)
    path = kes_path()
    exact = material("dahl", dahl_exponent=1.0)
    m1, _ = moment_along_path(exact, path)
    for n in (1 + offset, 1 - offset):
        m, _ = moment_along_path(material("dahl", dahl_exponent=n), path)
        assert np.abs(m - m1).max() < max(10 * offset, 1e-13) * exact.bending.dahl_moment, n


def test_a_material_files_law_must_be_a_law_name(tmp_path):
    from warpcloth.errors import SceneError

    path = tmp_path / "m.toml"
    path.write_text(
        '[material]\nname = "x"\nsource = "test"\nbending_law = ["dahl"]\ndensity_g_per_cm2 = 0.02\n'
        "tensile_gf_per_cm = [2000.0, 0.0, 0.0, 2.93e7]\nbending_rigidity_gf_cm2_per_cm = 0.1\n"
    )
    with pytest.raises(SceneError, match=r"m.toml: material.bending_law must be one of .*; got \['dahl'\]"):
        wc.load_scene("damped_swing", {"material.from_file": str(path)})
