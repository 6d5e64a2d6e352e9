"""Sweep summary metrics against a damped oscillator with known period and decrement."""

import numpy as np
import pytest

from warpcloth.metrics import swing_metrics


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
    import subprocess
    import sys

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
    trace.write_text("t_s,x_mm\n" + "\n".join(f"{t!r},{x * 1e3!r}" for t, x in zip(probes["t"], probes["laser_x"],
                                                                                   strict=True)))
    (from_trace,) = analyse(trace)
    for k in keys[:4]:
        assert from_trace[k] == pytest.approx(from_run[k], rel=1e-12), k
    done = subprocess.run([sys.executable, "-m", "warpcloth.cli", "analyse", str(trace), str(tmp_path / "r"),
                           str(tmp_path / "s"), "--csv", str(tmp_path / "t.csv")], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    import pandas as pd

    table = pd.read_csv(tmp_path / "t.csv")
    assert len(table) == 4 and table["first_period_s"].iloc[1] == pytest.approx(table["first_period_s"].iloc[3])


def test_a_strip_at_rest_has_no_swing():
    # a hanging strip's laser signal is rounding (1e-22 m): no half-cycles, no period
    import warpcloth as wc
    from warpcloth.metrics import swing_summary

    still = wc.simulate(wc.load_scene("damped_swing", ["release.enabled=false", "run.duration_s=0.5"]))
    metrics = swing_summary(still.t, still.probe("laser_x", 0), still.probe("tip_x", 0))
    assert metrics["n_half_cycles"] == 0 and np.isnan(metrics["first_period_s"])
