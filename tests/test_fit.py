"""Fitting the motion: synthetic measurements from runs with known parameters (plus noise
of a stated size) are recovered; the clamp-angle fit recovers the paper's θ(t); bad
requests are named."""

import copy
import json
import math

import numpy as np
import pytest
import warp as wp
from conftest import overrides, run_cli  # noqa: F401  (keeps Warp quiet)

import warpcloth as wc
from warpcloth.calibrate.motion_fit import SHIFT, fit_motion, free_parameters
from warpcloth.io.measured import LaserTrace, TrackedShapes
from warpcloth.scene import read_scene_file, set_field
from warpcloth.scene.clamp_motion import clamp_pieces, evaluate


def raw(name, **fields):
    data = read_scene_file(name)
    for key, value in fields.items():
        set_field(data, key.replace("__", "."), value)
    return data


def with_fields(data, fields):
    data = copy.deepcopy(data)
    for key, value in fields.items():
        set_field(data, key, value)
    return wc.scene_from_dict(data)


@pytest.mark.slow
def test_the_search_recovers_the_point_that_made_its_measurement():
    # The search alone: a laser trace made at the fit's own spacing (truth γ = 0.55 /s,
    # D1 = 0.025 gf·cm/cm, 300 Hz, σ = 0.2 mm), fitted there without the continuum estimate
    # (which would move the values to h → 0, away from this mesh's), so it says
    # spacing_limited. Measured: γ 0.5479 ± 0.0021, D1 0.02524 ± 0.00021, RMS 0.196 mm.
    base = raw("damped_swing", release__settle_time_s=0.3, run__duration_s=1.2)
    truth = {"damping.gamma_per_s": 0.55, "material.hysteresis_d1_gf_cm_per_cm": 0.025}
    result = wc.simulate(with_fields(base, truth))
    rng = np.random.default_rng(11)
    t = result.t[::2]
    measured = LaserTrace(t, result.probe("laser_x", 0)[::2] + rng.normal(0, 2e-4, len(t)))
    free = free_parameters("gamma,D1", wc.scene_from_dict(copy.deepcopy(base)))
    fit = fit_motion(base, measured, free, progress=False, continuum=False)
    assert fit.converged and fit.at_bound == [] and fit.status == "spacing_limited"
    assert len(fit.problems) == 1 and "continuum estimate not requested" in fit.problems[0]
    for name, value in truth.items():
        assert abs(fit.parameters[name] - value) < 3 * fit.sigma[name]
        assert abs(fit.parameters[name] - value) < 0.02 * value
        assert fit.sigma[name] < 0.02 * value
    assert fit.rms == pytest.approx(2e-4, rel=0.1)  # the residual is the noise, nothing systematic
    assert fit.launches <= 12
    stages = [h["stage"] for h in fit.history]
    assert stages[0] == "space filling" and "step" in stages


def tracked_markers(result, scene, offset, noise, rng):
    nc, h = scene.n_clamped, scene.spacing
    rows = []
    for f, t in enumerate(result.frame_times):
        if t < offset:
            continue
        for s in np.arange(0.0, 0.1001, 0.01):
            x, y = result.frames[f, 0, nc - 1 + round(s / h)] + rng.normal(0, noise, 2)
            rows.append((f, t - offset, s, x, y))
    d = np.array(rows)
    return TrackedShapes(d[:, 0].astype(int), d[:, 1], d[:, 2], d[:, 3], d[:, 4])


@pytest.mark.slow
def test_impulsive_rotation_centre_gamma_and_clock_are_recovered():
    # Truth: rotation centre 4.0 mm above the clamp edge, γ = 0.8 /s; markers every 10 mm
    # at 60 frames/s with σ = 0.3 mm; the camera clock starts 4 ms late. Measured:
    # dy 3.999 ± 0.026 mm, γ 0.78 ± 0.053, shift 4.15 ± 0.18 ms.
    base = raw("impulsive_rotation", run__duration_s=0.3)
    truth = {"clamp.rotation_centre_dy_mm": 4.0, "damping.gamma_per_s": 0.8}
    scene = with_fields(base, truth)
    measured = tracked_markers(wc.simulate(scene), scene, 0.004, 3e-4, np.random.default_rng(4))
    free = free_parameters("rotation_centre_dy_mm,gamma", wc.scene_from_dict(copy.deepcopy(base)))
    fit = fit_motion(base, measured, free, align_start_s=0.01, progress=False)
    truth[SHIFT] = 0.004
    for name, value in truth.items():
        assert abs(fit.parameters[name] - value) < 3 * fit.sigma[name]
    assert fit.sigma["clamp.rotation_centre_dy_mm"] < 0.1  # mm: the rotation centre is what this pins down
    assert fit.sigma[SHIFT] < 1e-3
    assert fit.rms == pytest.approx(3e-4, rel=0.1)


@pytest.mark.parametrize(
    "names, bounds, message",
    [
        ("stiffness", None, "neither a scene field nor one of"),
        ("strip.spacing_mm", None, "cannot vary between the strips"),
        ("material.name", None, "not a number"),
        ("gamma", "gamma=1", "not name=LOW:HIGH"),
        ("gamma", "gamma=2:1", "must be below"),
        ("gamma", "D1=0:1", "'D1' is not among the --free"),
        ("rotation_centre_dx_mm,release.hold_x_mm,clamp.table_t_s", None, "not a number"),
        ("", None, "at least one parameter"),
    ],
)
def test_bad_fit_requests_are_named(names, bounds, message):
    with pytest.raises(wc.ArgumentError, match=message):
        free_parameters(names, wc.load_scene("impulsive_rotation"), bounds)


def test_a_zero_parameter_needs_bounds():
    scene = wc.load_scene("damped_swing", ["material.hysteresis_d1_gf_cm_per_cm=0.0"])
    with pytest.raises(
        wc.ArgumentError, match="bounds: D1 is 0 in the scene, so no default range; give --bounds D1=LOW:HIGH"
    ):
        free_parameters("D1", scene)
    (d1,) = free_parameters("D1", scene, "D1=0:0.1")
    assert (d1.lower, d1.upper, d1.field) == (0.0, 0.1, "material.hysteresis_d1_gf_cm_per_cm")


@pytest.mark.slow
def test_cli_fits_the_bundled_examples(tmp_path):
    # The bundled data (scenes/data/make_motion_examples.py): encoder from the scene's
    # own θ(t) with 0.1° noise; markers of a rotation about a centre 4.0 mm up, γ 0.8.
    def cli(*args):
        return run_cli(*args, cwd=tmp_path)

    done = cli(
        "clamp",
        "fit-angle",
        "impulsive_rotation_encoder",
        "--scene",
        "impulsive_rotation",
        "-o",
        "fitted.toml",
        "--plot",
        "clamp.png",
    )
    assert done.returncode == 0, done.stderr
    assert "form: quartic, line, rest" in done.stdout and "status: converged" in done.stdout
    fitted = wc.load_scene(tmp_path / "fitted.toml")
    quartic, second = fitted.clamp.segments
    t = np.linspace(0.0, 0.2, 401)
    truth = np.where(t < 0.05, 3.2e4 * t**4, 0.2 + 16.0 * (np.minimum(t, 0.12) - 0.05))
    assert np.abs(evaluate(*clamp_pieces(fitted.clamp), t) - truth).max() < np.radians(0.1)  # the noise
    assert second.theta_coefficients_si[1] == pytest.approx(16.0, rel=0.01)
    assert second.t_end_s == pytest.approx(0.12, abs=2e-3)
    done = cli(
        "fit",
        "impulsive_rotation",
        "--measured",
        "impulsive_rotation_shapes",
        "--free",
        "gamma,rotation_centre_dy_mm",
        "--align-start",
        "0.01",
        "--out",
        "fit",
        "--no-progress",
        "--bootstrap",
        "300",
    )
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "fit" / "fit.json").read_text())
    # the markers are of a 0.625 mm run: the fit at the scene's 2.5 mm, extrapolated to
    # h → 0 (issue 34), finds the truth within 2 σ_total, σ_total² = σ_noise² + σ_mesh²
    assert "continuum limit h → 0 (fitted at strip.spacing_mm = 2.5; observed order" in done.stdout
    assert result["status"] == "converged" and result["problems"] == []
    assert result["continuum"]["status"] == "extrapolated"
    for name, truth in {"clamp.rotation_centre_dy_mm": 4.0, "damping.gamma_per_s": 0.8, SHIFT: 0.004}.items():
        p = result["parameters"][name]
        assert abs(p["value"] - truth) <= 2 * p["sigma"], name
        assert p["sigma"] == pytest.approx(math.hypot(p["sigma_noise"], p["sigma_mesh"]))
    dy, noise, boot = (
        result["parameters"]["clamp.rotation_centre_dy_mm"][k] for k in ("value", "sigma_noise", "sigma_bootstrap")
    )
    assert 0.6 < boot / noise < 1.6  # white marker noise: the bootstrap agrees with Gauss–Newton
    assert result["inputs"]["measured"]["sha256"] and result["provenance"]["warp"] == wp.__version__
    for name in ("best.toml", "history.csv", "residuals.csv", "overlay.png"):
        assert (tmp_path / "fit" / name).is_file()
    best = wc.load_scene(tmp_path / "fit" / "best.toml")  # the continuum values on the finest level's mesh
    assert best.clamp.rotation_centre_dy_mm == pytest.approx(dy) and best.run.duration_s == 0.5
    assert best.strip.spacing_mm == result["continuum"]["extrapolated_from_mm"][1] == 1.25
    done = cli("fit", "impulsive_rotation", "--measured", "impulsive_rotation_shapes", "--free", "bogus")
    assert done.returncode == 2 and "--free" in done.stderr


def test_markers_beyond_the_free_end_are_refused():
    base = raw("impulsive_rotation", run__duration_s=0.1)
    markers = TrackedShapes(np.array([0, 1]), np.array([0.0, 0.05]), np.array([0.05, 0.12]), np.zeros(2), np.zeros(2))
    free = free_parameters("gamma", wc.scene_from_dict(copy.deepcopy(base)))
    beyond = "measurement: a marker at s = 120 mm lies beyond the free end"
    with pytest.raises(wc.ArgumentError, match=beyond) as raised:
        fit_motion(base, markers, free, progress=False)
    assert "header in metres" not in str(raised.value)
    # millimetres under a header in metres: a thousand strips long, which names the unit
    in_metres = TrackedShapes(np.array([0, 1]), np.array([0.0, 0.05]), np.array([5.0, 95.0]), np.zeros(2), np.zeros(2))
    unit = r"s = 5000 mm .* millimetres under a header in metres\? head the column s_mm"
    with pytest.raises(wc.ArgumentError, match=unit):
        fit_motion(base, in_metres, free, progress=False)


@pytest.mark.slow
def test_a_fit_that_ends_on_a_bound_says_so_and_exits_non_zero(tmp_path):
    # Truth γ = 0.55 /s in the bundled trace; bounds that exclude it pin γ at 5: the search
    # ends there at many times the noise, and that must not read as a fitted value.
    done = run_cli(
        "fit",
        "damped_swing",
        "--measured",
        "damped_swing_laser",
        "--free",
        "gamma",
        "--bounds",
        "gamma=5:6",
        "--max-iterations",
        "3",
        "--out",
        "fit",
        "--no-progress",
        cwd=tmp_path,
    )
    assert done.returncode == 4, done.stderr
    assert "not a fit (at_bound): damping.gamma_per_s = 5 ended on a bound (5:6)" in done.stderr
    result = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert result["status"] == "at_bound" and result["parameters"]["damping.gamma_per_s"]["at_bound"] is True


def test_only_a_continuum_estimate_is_converged():
    from warpcloth.calibrate.motion_fit import FitResult

    def judged(continuum, mesh_note=""):
        fit = FitResult(
            {"damping.gamma_per_s": 0.5},
            {"damping.gamma_per_s": 0.01},
            [[1.0]],
            1e-4,
            0.0,
            100,
            1,
            1,
            0.0,
            converged=True,
            noise=1e-4,
            continuum=continuum,
            mesh_note=mesh_note,
        )
        fit.judge(0)
        return fit

    assert judged({"status": "extrapolated"}).status == "converged"
    unresolved = judged({"status": "unresolved", "note": "the simulated motion converges at order 0.9"})
    assert unresolved.status == "spacing_limited"
    assert unresolved.problems == [
        "no continuum estimate: the simulated motion converges at order 0.9; the values are the fit at the "
        "scene's spacing"
    ]
    assert judged({"status": "not requested"}).status == "spacing_limited"
    assert judged({}).status == "spacing_limited"
    dependent = judged({}, mesh_note="the tagawa2003 law's hysteresis depends on the mesh")
    assert dependent.status == "mesh_dependent" and dependent.problems[0].endswith("not fabric properties")


def test_a_given_noise_the_data_contradict_is_refused_or_named(tmp_path):
    # issue 39: --noise 1e4 (10 m on a 50 mm swing) turned a poor fit into "converged"
    from warpcloth import bodies
    from warpcloth.calibrate.motion_fit.verdict import check_given_noise, measurement_noise

    laser = bodies.named("strip")("read_measurement", "damped_swing_laser")
    shown = measurement_noise(laser)  # 0.19 mm
    check_given_noise(laser, 3 * shown)  # a calibration's systematic share: taken as given
    with pytest.warns(wc.errors.PlausibilityWarning, match=r"--noise 5 mm is 2\d\.\d× the noise the data"):
        check_given_noise(laser, 5e-3)
    with pytest.raises(wc.ArgumentError, match=r"noise: 1e\+04 mm is as large as the measured motion itself"):
        check_given_noise(laser, 10.0)
    done = run_cli(
        "fit",
        "damped_swing",
        "--measured",
        "damped_swing_laser",
        "--free",
        "gamma",
        "--noise",
        "1e4",
        "--out",
        tmp_path / "fit",
    )
    assert done.returncode == 2 and "--noise: 1e+04 mm is as large as the measured motion" in done.stderr
    assert not (tmp_path / "fit").exists()
