"""Sweep summary metrics against a damped oscillator with known period and decrement."""

import numpy as np
import pytest
from conftest import run_cli

from warpcloth.metrics import swing_metrics, swing_summary


def damped_cosine(rate, zeta, period=0.52, duration=1.5, amplitude=0.05):
    """x = A e^{-ζωt}(cos ω_d t + (ζω/ω_d) sin ω_d t), released at rest at t = 0 and turning
    exactly every π/ω_d, sampled at ``rate``; with its period 2π/ω_d, its log decrement per
    half-cycle π ζ / √(1 − ζ²) and its first half-cycle amplitude A (1 + e^{-decrement}) / 2."""
    t = np.arange(0, duration, 1 / rate)
    omega = 2 * np.pi / period
    wd = omega * np.sqrt(1 - zeta**2)
    x = amplitude * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    decrement = np.pi * zeta / np.sqrt(1 - zeta**2)
    return t, x, 2 * np.pi / wd, decrement, amplitude * (1 + np.exp(-decrement)) / 2


@pytest.mark.parametrize("zeta", [0.005, 0.02, 0.08])
def test_swing_metrics_of_a_damped_oscillator(zeta):
    # x = e^{-ζωt}(cos ω_d t + (ζω/ω_d) sin ω_d t) starts at rest and turns exactly every
    # π/ω_d; its log decrement per half-cycle is π ζ / √(1 − ζ²). Sampled at 600 Hz like
    # the laser probe; parabolic refinement of the turning points makes the period exact
    # to ~1e-5 s (bound 1e-4 relative) and the decrement to 1e-6.
    t = np.arange(0, 6, 1 / 600)
    omega = 2 * np.pi / 0.5
    wd = omega * np.sqrt(1 - zeta**2)
    x = 0.05 * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    m = swing_metrics(t, x)
    assert m["first_period_s"] == pytest.approx(2 * np.pi / wd, rel=1e-4)
    assert m["mean_log_decrement"] == pytest.approx(np.pi * zeta / np.sqrt(1 - zeta**2), rel=1e-4)
    decrement = np.pi * zeta / np.sqrt(1 - zeta**2)
    assert m["half_cycle_amplitude_m"][0] == pytest.approx(0.05 * (1 + np.exp(-decrement)) / 2, rel=1e-4)
    assert m["n_half_cycles"] == len(m["log_decrement"]) + 1


@pytest.mark.parametrize("zeta", [0.005, 0.02, 0.08])
@pytest.mark.parametrize("period", [0.45, 0.5, 0.52, 0.55])  # turning points at different sampling phases
def test_noise_free_turning_points_at_300_hz_are_unbiased(zeta, period):
    # The least-squares window spans ±5 % of the period (16 samples at 300 Hz); its model's
    # cubic and quartic terms (those of a damped cosine) keep it exact on one: measured
    # ≤ 3.4e-6 of the period, ≤ 6e-7 of the amplitude and of the decrement (a plain
    # parabola over the window: 2.8e-4 of the period at ζ = 0.08, 2e-5 of the amplitude).
    t, x, true_period, decrement, first_amplitude = damped_cosine(300, zeta, period, duration=3)
    m = swing_metrics(t, x)
    assert m["first_period_s"] == pytest.approx(true_period, rel=1e-5)
    assert m["first_amplitude_m"] == pytest.approx(first_amplitude, rel=2e-6)
    assert m["mean_log_decrement"] == pytest.approx(decrement, rel=2e-6)


@pytest.mark.parametrize("rate", [300, 600])
def test_noisy_period_scatters_as_its_stated_uncertainty(rate):
    # A laser trace's noise (σ = 0.2 mm on a 50 mm swing of 0.52 s): over 200 seeds the
    # first period's error scatters as the uncertainty propagated from the fit says (0.54
    # ms at 300 Hz, 0.37 ms at 600 Hz; three samples scattered 4 ms at 300 Hz, and at
    # 600 Hz noise made false turning points), unbiased, and so do the amplitudes (three
    # samples through the noisy top read them 0.09 mm too large).
    t, x, true_period, _, first_amplitude = damped_cosine(rate, 0.02)
    rng = np.random.default_rng(rate)
    sigma, n = 2e-4, 200
    metrics = [swing_metrics(t, x + rng.normal(0, sigma, len(t)), noise=sigma) for _ in range(n)]
    error = np.array([m["first_period_s"] for m in metrics]) - true_period
    stated = np.array([m["first_period_u_s"] for m in metrics])
    amplitude_error = np.array([m["first_amplitude_m"] for m in metrics]) - first_amplitude
    assert stated.mean() < 0.6e-3
    assert 0.8 < error.std() / stated.mean() < 1.25
    assert abs(error.mean()) < 3 * error.std() / np.sqrt(n)
    assert abs(amplitude_error.mean()) < 3 * amplitude_error.std() / np.sqrt(n)


def test_bundled_laser_period_is_its_truth_within_its_uncertainty():
    # scenes/data/make_motion_examples.py made the trace from the damped swing with
    # γ = 0.55 /s, D1 = 0.025 (600 Hz probes taken every other sample, σ = 0.2 mm); the
    # same ruler on that noise-free run gives 0.51915 s, the trace 0.52101 ± 0.00089 s
    # (2.1 u: this draw of the noise; over 400 draws the error is 0.02 ± 0.86 ms). Three
    # samples per turning point read 0.51349 s, 7.6 u from the truth.
    import warpcloth as wc
    from warpcloth.calibrate.analysis import analyse

    truth = wc.simulate(
        wc.load_scene(
            "damped_swing",
            {"damping.gamma_per_s": 0.55, "run.duration_s": 1.5, "material.hysteresis_d1_gf_cm_per_cm": 0.025},
        )
    )
    expected = swing_summary(truth.t, truth.probe("laser_x", 0), truth.probe("tip_x", 0))["first_period_s"]
    (row,) = analyse("damped_swing_laser")
    assert row["first_period_u_s"] < 1e-3
    assert abs(row["first_period_s"] - expected) < 3 * row["first_period_u_s"]


def test_no_swing_gives_nan_not_an_error():
    m = swing_metrics(np.arange(10) / 600, np.zeros(10))
    assert np.isnan(m["first_period_s"]) and m["n_half_cycles"] == 0


def test_ripples_near_turning_points_are_not_half_cycles():
    # The sweep found laser traces of nearly undamped strips whose higher modes put a
    # ripple on the swing (a 0.06 mm wiggle near a 33 mm turning point); the old
    # detector took the wiggle for two half-cycles and stopped there. A 0.5 % ripple at
    # 7.3× the frequency must leave every half-cycle of the 0.5 s swing in place.
    t = np.arange(0, 3, 1 / 600)
    omega = 2 * np.pi / 0.5
    zeta = 0.01
    wd = omega * np.sqrt(1 - zeta**2)
    x = 0.05 * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    rippled = x + 2.5e-4 * np.sin(7.3 * omega * t)
    clean, noisy = swing_metrics(t, x), swing_metrics(t, rippled)
    assert clean["n_half_cycles"] == noisy["n_half_cycles"] == 11  # 12 turning points in 3 s
    assert noisy["mean_log_decrement"] == pytest.approx(clean["mean_log_decrement"], rel=0.05)
    assert noisy["first_period_s"] == pytest.approx(clean["first_period_s"], rel=0.01)


def test_one_ruler_for_runs_sweeps_and_measured_traces(tmp_path):
    # The sweep summary, `analyse` of a run of the same scene, and `analyse` of that run's
    # laser line written out as a measured trace give the same first period and decrements.

    import warpcloth as wc
    from warpcloth.calibrate.analysis import analyse
    from warpcloth.scene import read_scene_file

    base = read_scene_file("damped_swing")
    base["run"]["duration_s"] = 1.2
    sweep = wc.expand(base | {"sweep": {"grid": {"damping.gamma_per_s": [0.3, 0.9]}}})
    wc.run_sweep(sweep, tmp_path / "s", workers=0, progress=False)
    from_sweep = analyse(tmp_path / "s")
    wc.simulate(sweep.scenes[1], out=tmp_path / "r")
    (from_run,) = analyse(tmp_path / "r")
    keys = ("first_period_s", "first_amplitude_mm", "mean_log_decrement", "n_half_cycles", "log_decrement")
    assert 3 <= from_run["n_half_cycles"] <= 6  # the swing's half-cycles, not ripples
    # equal up to probes.csv's 10-digit times
    for k in keys[:4]:
        assert from_run[k] == pytest.approx(from_sweep[1][k], rel=1e-9), k
    probes = wc.load_recording(tmp_path / "r").probes
    trace = tmp_path / "lab.csv"
    trace.write_text(
        "t_s,x_mm\n" + "\n".join(f"{t!r},{x * 1e3!r}" for t, x in zip(probes["t"], probes["laser_x"], strict=True))
    )
    (from_trace,) = analyse(trace)
    for k in keys[:4]:
        assert from_trace[k] == pytest.approx(from_run[k], rel=1e-12), k
    # a measured trace's period has the uncertainty of the noise it shows (here rounding
    # and ripple: microseconds); a simulation's has none
    assert from_trace["first_period_u_s"] < 1e-5 and np.isnan(from_run["first_period_u_s"])
    done = run_cli("analyse", str(trace), str(tmp_path / "r"), str(tmp_path / "s"), "--csv", str(tmp_path / "t.csv"))
    assert done.returncode == 0, done.stderr
    import pandas as pd

    table = pd.read_csv(tmp_path / "t.csv")
    assert len(table) == 4 and table["first_period_s"].iloc[1] == pytest.approx(table["first_period_s"].iloc[3])
    assert table["first_period_u_s"].notna().tolist() == [True, False, False, False]
    assert "first_period_u_s" in done.stdout.splitlines()[0]


def test_a_strip_at_rest_has_no_swing():
    # a hanging strip's laser signal is rounding (1e-22 m): no half-cycles, no period
    import warpcloth as wc

    still = wc.simulate(wc.load_scene("damped_swing", ["release.enabled=false", "run.duration_s=0.5"]))
    metrics = swing_summary(still.t, still.probe("laser_x", 0), still.probe("tip_x", 0))
    assert metrics["n_half_cycles"] == 0 and np.isnan(metrics["first_period_s"])


def test_analyse_measures_every_input_on_one_window(tmp_path):
    # Issue 22: a record twice as long as another was measured on all of it, and a swing
    # whose decrement changes with amplitude (hysteresis) then reads another mean
    # decrement. Two traces of one swing (decrement falling with amplitude), 1.5 s and 3 s.
    import warpcloth as wc
    from warpcloth.calibrate.analysis import analyse

    t = np.arange(0, 3.0 + 1e-9, 1 / 300)
    x = 50.0 / (1 + 2 * t) * np.cos(2 * np.pi * t / 0.52)
    for name, end in (("short.csv", 1.5), ("long.csv", 3.0)):
        keep = t <= end + 1e-9
        (tmp_path / name).write_text(
            "t_s,x_mm\n" + "\n".join(f"{a:.6f},{v:.6f}" for a, v in zip(t[keep], x[keep], strict=True))
        )
    short, long = str(tmp_path / "short.csv"), str(tmp_path / "long.csv")
    (alone,) = analyse(long)
    rows = analyse([short, long])
    assert [(r["from_s"], r["to_s"]) for r in rows] == [(0.0, 1.5), (0.0, 1.5)]
    for key in ("first_period_s", "first_amplitude_mm", "mean_log_decrement", "n_half_cycles"):
        assert rows[0][key] == rows[1][key], key
    assert abs(alone["mean_log_decrement"] / rows[0]["mean_log_decrement"] - 1) > 0.1  # what the overlap prevents
    chosen = analyse([short, long], t_from=0.3, t_to=1.2)
    assert [(r["from_s"], r["to_s"]) for r in chosen] == [(0.3, 1.2)] * 2 and chosen[0]["n_half_cycles"] > 0
    with pytest.raises(wc.ArgumentError, match=r"t_to: 3 s is after the end of .*short.csv \(1.5 s\)"):
        analyse([short, long], t_to=3.0)
    with pytest.raises(wc.ArgumentError, match=r"t_from: -1 s is before the start of"):
        analyse([short, long], t_from=-1.0)
    with pytest.raises(wc.ArgumentError, match=r"t_from: 1 s is not before the window's end 0.5 s \(--to\)"):
        analyse([short, long], t_from=1.0, t_to=0.5)
    done = run_cli("analyse", short, long, "--from", "2")
    assert done.returncode == 2 and "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "--from: 2 s is not before the window's end 1.5 s (the end of" in done.stderr


def test_analyse_gives_a_strip_that_diverged_before_t0_a_row_of_nans(tmp_path):
    # strip 1 (400× the bending rigidity, imex at 2e-4 s) diverges during the hold: it has no
    # sample after t = 0, so it gets NaNs and no say in the window, not a traceback
    import warpcloth as wc
    from warpcloth.calibrate.analysis import analyse

    fields = ["run.duration_s=0.3", 'integrator.scheme="imex"', "integrator.dt_s=2e-4"]
    scenes = [
        wc.load_scene("damped_swing", fields),
        wc.load_scene("damped_swing", [*fields, "material.bending_rigidity_gf_cm2_per_cm=40"]),
    ]
    result = wc.simulate(scenes, out=tmp_path / "r", on_divergence="record")
    assert [d.strip for d in result.diverged] == [1] and result.diverged[0].phase != "record"
    good, gone = analyse(tmp_path / "r")
    assert (good["from_s"], good["to_s"]) == (0.0, 0.3) and good["first_amplitude_mm"] > 10
    assert gone["n_half_cycles"] == 0 and np.isnan(gone["first_amplitude_mm"])
