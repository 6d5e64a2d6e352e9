"""Forward Euler (the paper's eqs. 5-6) vs semi-implicit Euler at the paper's dt."""

import re

import pytest
from conftest import overrides

import warpcloth as wc


def hanging(scheme):
    # Default material, no damping, released straight: gravity sets off tensile waves.
    return wc.load_scene(
        "damped_swing",
        overrides(
            release__enabled=False,
            damping__gamma_per_s=0.0,
            integrator__dt_s=1e-7,
            integrator__scheme=scheme,
            run__duration_s=0.3,
        ),
    )


def test_forward_euler_diverges_at_paper_dt_without_damping():
    # |1 + iω dt| > 1 amplifies every undamped mode: the energy budget stops closing long
    # before the strain passes 0.25 (at t = 0.186 s). The run must stop and say where,
    # not write NaNs.
    with pytest.raises(wc.DivergenceError) as info:
        wc.simulate(hanging("forward"))
    report = info.value.diverged[0]
    assert report.strip == 0 and report.quantity.startswith("energy budget residual")
    assert 0.0 < report.time_s < 0.186
    message = str(info.value)
    assert "strip 0 diverged after t = 0, at t =" in message
    assert "integrator.dt_s" in message and "semi_implicit" in message
    recorded = info.value.result
    kept = recorded.t <= report.time_s
    assert kept.sum() > 10
    assert all(recorded.probe(name, 0)[kept].dtype.kind == "f" for name in ("tip_x", "tensile"))


def test_semi_implicit_stays_bounded_at_paper_dt():
    result = wc.simulate(hanging("semi_implicit"))
    # Tensile energy stays at the static-sag level (measured max 6.7e-8 J).
    assert result.probe("tensile", 0).max() < 1e-6
    assert abs(result.probe("tip_x", 0)).max() < 1e-9


def past_the_check(scene, dt):
    """Run ``scene`` at ``dt`` through the simulation core, which takes any dt (the scene
    layer is what refuses an unstable one)."""
    from warpcloth.scene import build_batch
    from warpcloth.strip import SemiImplicitEulerSolver, simulate_batch

    batch = build_batch([scene])
    solver = SemiImplicitEulerSolver(batch.model, dt=dt, divergence_strain=scene.integrator.divergence_strain)
    return simulate_batch(
        batch.model, batch.control, solver, batch.recorder, on_divergence="record", keep_frames=False, threads=1
    )


@pytest.mark.parametrize(
    "material, free_length_mm", [("wool90-nylon10", 100.0), ("polyester-taffeta", 100.0), ("wool90-nylon10", 10.0)]
)
def test_the_refused_step_is_the_stretching_stability_limit(material, free_length_mm):
    # h·√(ρ_A/a1)/cos(π/4N) (5.0907e-5 s for the default material at h = 5 mm and N = 20 free
    # nodes, 1.3369e-5 s for polyester-taffeta; 5.50e-5 s at N = 2, where the cosine is
    # 8 % from 1) is where the undamped hanging strip stops being stable: a run at 0.98
    # of it stays at the static sag, one at 1.02 of it diverges within 0.2 s.
    from warpcloth.scene import to_si
    from warpcloth.strip.solvers import SemiImplicitEulerSolver

    strip = dict(
        release__enabled=False,
        strip__free_length_mm=free_length_mm,
        material__from_file=material,
        output__laser_height_mm=-0.8 * free_length_mm,
    )  # on the strip, however short
    scene = wc.load_scene("damped_swing", overrides(damping__gamma_per_s=0.0, run__duration_s=0.2, **strip))
    limit = SemiImplicitEulerSolver.step_limit(to_si(scene.material), scene.spacing, scene.n_nodes - scene.n_clamped)
    assert not past_the_check(scene, 0.98 * limit).diverged
    assert past_the_check(scene, 1.02 * limit).diverged
    with pytest.raises(
        wc.SceneError,
        match=r"integrator.dt_s: .* above the semi_implicit scheme's stability "
        r"limit .*integrator.scheme = \"imex\"",
    ) as info:
        wc.load_scene("damped_swing", overrides(integrator__dt_s=1.02 * limit, **strip))
    # the advice is rounded down: a step of what it says runs
    advised = float(re.search(r"a dt_s of at most (\S+) s", str(info.value)).group(1))
    assert 0.999 * limit < advised <= limit
    wc.load_scene("damped_swing", overrides(integrator__dt_s=advised, **strip))
    # imex takes the stretching implicitly: no such bound
    wc.load_scene("damped_swing", overrides(integrator__dt_s=1.02 * limit, integrator__scheme="imex", **strip))


def test_a_recorded_run_past_the_limit_stays_readable(tmp_path):
    # the step check is for runs about to start: a stored scene is read back as it ran

    run = tmp_path / "run"
    wc.simulate(
        wc.load_scene(
            "damped_swing",
            overrides(integrator__scheme="imex", integrator__dt_s=1e-4, run__duration_s=0.05, release__enabled=False),
        ),
        out=run,
    )
    stored = run / "scene.toml"
    stored.write_text(re.sub(r'scheme = "imex"', 'scheme = "semi_implicit"', stored.read_text()))
    assert wc.load_recording(run).scenes[0].integrator.scheme == "semi_implicit"
    with pytest.raises(wc.SceneError, match=rf"above the semi_implicit .*\({re.escape(str(stored))}, line \d+\)"):
        wc.load_scene(stored)


def test_the_slack_above_the_limit_is_for_softening_laws_only():
    from warpcloth.scene import to_si
    from warpcloth.strip.solvers import SemiImplicitEulerSolver

    scene = wc.load_scene("damped_swing")
    limit = SemiImplicitEulerSolver.step_limit(to_si(scene.material), scene.spacing, scene.n_nodes - scene.n_clamped)
    with pytest.raises(wc.SceneError, match="above the semi_implicit scheme's stability limit"):
        wc.load_scene("damped_swing", overrides(integrator__dt_s=1.0005 * limit))
    # a softening quartic (a2 < 0): strained, its limit can lie up to ~5e-4 above the unstrained one
    wc.load_scene(
        "damped_swing",
        overrides(integrator__dt_s=1.0005 * limit, material__tensile_gf_per_cm=[2000.0, -1e4, 0.0, 2.93e7]),
    )
