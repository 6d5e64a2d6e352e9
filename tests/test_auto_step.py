"""integrator.dt_s = "auto": the bending stability estimate against runs, the choice, its
accuracy against a fine solution, and its refusals (docs/model.md §9.6)."""

import dataclasses
import math

import numpy as np
import pytest
from conftest import overrides

import warpcloth as wc
from warpcloth.errors import SceneError
from warpcloth.scene import to_si
from warpcloth.scene.step import STABILITY_MARGIN, choose_step, describe_step, requesting_auto
from warpcloth.strip.stability import is_hysteretic, stiffest_tangent


@pytest.mark.parametrize(
    "name, grip, expected",
    [
        ("damped_swing", {}, 1.743e-3),
        ("impulsive_rotation", {}, 4.461e-4),
        ("damped_swing", {"clamp.grip_length_mm": 20.0, "clamp.grip_bending_factor": 3.0}, 1.133e-3),
        ("impulsive_rotation", {"clamp.grip_length_mm": 20.0, "clamp.grip_bending_factor": 3.0}, 2.667e-4),
    ],
)
def test_the_bending_estimate_is_where_an_elastic_imex_run_stops_being_stable(name, grip, expected):
    # Elastic (D1 = 0), stretching implicit: explicit bending and the tension's transverse
    # stiffness are what is left. The linearised hanging chain, with the grip's stiffer
    # root hinges where there is one, says where the run stops being stable, within 3 %.
    fields = dict(
        material__hysteresis_d1_gf_cm_per_cm=0.0,
        integrator__scheme="imex",
        output__frame_rate_hz=10.0,
        output__probes_per_frame=1,
    )
    extra = [f"{k}={v!r}" for k, v in grip.items()]
    scene = wc.load_scene(name, overrides(**fields) + extra)
    limit = choose_step(requesting_auto([scene])).bound.seconds
    assert limit == pytest.approx(expected, rel=1e-3)
    for factor, diverges in ((0.97, False), (1.03, True)):
        scene = wc.load_scene(name, overrides(**fields, integrator__dt_s=factor * limit) + extra)
        assert bool(wc.simulate(scene, on_divergence="record").diverged) is diverges, factor


def test_the_law_tangent_and_loop_come_from_the_law_kernel():
    scene = wc.load_scene("damped_swing", overrides(material__bending_law="masing"))
    material = to_si(scene.material)
    # a Masing branch starts at slope D + α·D1 (docs/model.md §4.10)
    assert stiffest_tangent(material) == pytest.approx(
        material.bending_rigidity + material.bending.hysteresis_alpha * material.bending.hysteresis_d1, rel=1e-6
    )
    assert is_hysteretic(material)
    assert not is_hysteretic(dataclasses.replace(material, bending=material.bending.replace(hysteresis_d1=0.0)))


def test_auto_divides_the_probe_interval_and_stays_under_both_bounds():
    for scheme in ("semi_implicit", "imex"):
        scene = wc.load_scene(
            "damped_swing",
            overrides(integrator__dt_s="auto", integrator__scheme=scheme, material__bending_law="masing"),
        )
        dt = scene.integrator.dt_s
        assert scene.integrator.dt_chosen_by == "auto"
        steps = scene.output_interval / dt
        assert abs(steps - round(steps)) < 1e-9
        choice = choose_step(requesting_auto([scene]))
        assert dt <= choice.bound.seconds * STABILITY_MARGIN[choice.bound.exact]
        if scheme == "imex":
            assert dt <= 2e-4 and choice.bound.mode == "bending"
        else:
            assert choice.bound.mode == "stretching" and choice.bound.exact
            assert dt > 0.85 * choice.bound.seconds  # the longest whole fraction under the margin
        assert describe_step(scene).startswith(f"integrator.dt_s = auto: {dt:.4e} s")


def test_a_recorded_auto_scene_reruns_with_the_same_step(tmp_path):
    scene = wc.load_scene("impulsive_rotation", overrides(integrator__dt_s="auto", run__duration_s=0.05))
    result = wc.simulate(scene, out=tmp_path / "run")
    again = wc.load_scene(tmp_path / "run" / "scene.toml")
    assert again.integrator.dt_s == scene.integrator.dt_s and again.integrator.dt_chosen_by == "auto"
    assert result.strip_steps > 0


@pytest.mark.parametrize("name, scheme", [("damped_swing", "semi_implicit"), ("impulsive_rotation", "imex")])
def test_the_auto_step_is_within_its_stated_accuracy(name, scheme):
    # The evidence auto rests on: within 0.2 % of the tip's excursion of a fine explicit
    # solution (measured 0.014 % on the swing, 0.069 % on the rotation with imex over their
    # full records; here shortened).
    fields = dict(material__bending_law="masing", run__duration_s=0.6, output__probes_per_frame=2)
    fine = wc.simulate(wc.load_scene(name, overrides(**fields, integrator__dt_s=2e-6)))
    auto = wc.simulate(wc.load_scene(name, overrides(**fields, integrator__dt_s="auto", integrator__scheme=scheme)))
    excursion = np.ptp(fine.probe("tip_x", 0))
    error = max(np.abs(auto.probe(p, 0) - fine.probe(p, 0)).max() for p in ("tip_x", "tip_y"))
    assert error < 2e-3 * excursion


def test_a_sweep_shares_one_auto_step_the_strictest_variant_sets():
    # the stretching limit grows as √ρ_A: the lighter variant sets the sweep's one step
    raw = wc.scene.read_scene_file("damped_swing")
    raw["integrator"]["dt_s"] = "auto"
    raw["sweep"] = {"grid": {"material.density_g_per_cm2": [0.01, 0.02, 0.04]}}
    sweep = wc.expand(raw)
    alone = [choose_step(requesting_auto([s])).dt_s for s in sweep.scenes]
    assert len(set(alone)) == 3
    assert {s.integrator.dt_s for s in sweep.scenes} == {min(alone)}


def test_a_step_auto_chose_for_another_scene_is_refused_not_reused(tmp_path):
    # a recorded auto scene rerun at a finer spacing would keep a step 5× too long for it
    scene = wc.load_scene(
        "damped_swing", overrides(integrator__dt_s="auto", run__duration_s=0.02, release__settle_time_s=0.01)
    )
    wc.simulate(scene, out=tmp_path / "run")
    with pytest.raises(
        SceneError,
        match=r"integrator\.dt_s: 4\.5045e-05 s was chosen by dt_s = \"auto\" for another "
        r"scene .* auto chooses 1\.1",
    ):
        wc.load_scene(tmp_path / "run" / "scene.toml", ["strip.spacing_mm=1.25"])
    again = wc.load_scene(tmp_path / "run" / "scene.toml", ["strip.spacing_mm=1.25", 'integrator.dt_s="auto"'])
    assert again.integrator.dt_s < scene.integrator.dt_s / 3
    # and a Scene still asking for auto (made in Python) has its step chosen by simulate
    asking = dataclasses.replace(
        scene, integrator=dataclasses.replace(scene.integrator, dt_s="auto", dt_chosen_by="scene")
    )
    assert wc.simulate(asking).strip_steps == wc.simulate(scene).strip_steps


def test_auto_is_refused_where_no_step_is_both_stable_and_accurate():
    with pytest.raises(SceneError, match=r"integrator\.dt_s.*forward"):
        wc.load_scene("damped_swing", overrides(integrator__dt_s="auto", integrator__scheme="forward"))
    # the paper's law keeps a floor under imex that no dt removes (§9.5)
    with pytest.raises(SceneError, match=r"integrator\.dt_s.*no accurate imex step for the tagawa2003"):
        wc.load_scene("damped_swing_paper", overrides(integrator__dt_s="auto", integrator__scheme="imex"))
    elastic = wc.load_scene(
        "damped_swing",
        overrides(integrator__dt_s="auto", integrator__scheme="imex", material__hysteresis_d1_gf_cm_per_cm=0.0),
    )
    assert math.isclose(elastic.integrator.dt_s, elastic.output_interval / 9)
    with pytest.raises(SceneError, match=r"expected a number or 'auto', got 'fast'"):
        wc.load_scene("damped_swing", overrides(integrator__dt_s="fast"))


def test_the_papers_law_runs_imex_trapezoidal_at_auto_at_a_shorter_step():
    # the trapezoidal rule keeps a tenth of imex's floor (§9.5.1): auto takes it, capped at
    # the 5e-4 s it is measured within 0.2 % at, and with a law without return-point memory
    # at the 1.12e-4 s the bundled sweep's 200 variants are within 0.2 % at (worst 0.162 %
    # at 1/15 of the probe interval, 1.11e-4 s)
    from warpcloth.scene.step import choose_step

    scene = wc.load_scene("damped_swing_paper", overrides(integrator__scheme="imex_trapezoidal"))
    choice = choose_step([scene])
    assert math.isclose(choice.dt_s, choice.interval_s / 15)
    assert (
        "the 0.000112 s up to which imex_trapezoidal is measured within 0.2 % with the tagawa2003 law, "
        "which has no return-point memory (docs/model.md §9.5.1, §9.6)" in choice.describe()
    )
    masing = choose_step([wc.load_scene("damped_swing", overrides(integrator__scheme="imex_trapezoidal"))])
    assert masing.memoryless_laws is None and math.isclose(masing.dt_s, masing.interval_s / 4)
    assert "the 0.0005 s up to which imex_trapezoidal is measured within 0.2 % (docs" in masing.describe()
    with pytest.raises(SceneError, match=r'use scheme = "imex_trapezoidal"'):
        wc.load_scene("damped_swing_paper", overrides(integrator__dt_s="auto", integrator__scheme="imex"))


def test_a_fit_chooses_its_step_over_the_corners_of_its_box():
    from warpcloth.calibrate.motion_fit import Objective, free_parameters
    from warpcloth.io.measured import LaserTrace

    base = wc.scene.read_scene_file("damped_swing")
    base["integrator"]["dt_s"] = "auto"
    scene = wc.scene.scene_from_dict(base)
    density = scene.material.density_g_per_cm2
    free = free_parameters("density", scene, f"density={density / 2}:{density}")
    objective = Objective(base, LaserTrace(np.linspace(0, 0.5, 31), np.zeros(31)), free)
    # the stretching limit is h·√(ρ_A/a1)/cos(π/4N): the box's lightest corner sets the step
    light = wc.scene.scene_from_dict({**base, "material": {**base["material"], "density_g_per_cm2": density / 2}})
    assert objective.scene.integrator.dt_s == light.integrator.dt_s < scene.integrator.dt_s
    assert objective.scene.integrator.dt_chosen_by == "auto"
