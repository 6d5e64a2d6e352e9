"""Figures and renders, headless: files exist, are not blank, and show the strip where
the simulation put it."""

import subprocess
import sys

import numpy as np
import pytest
from conftest import overrides
from PIL import Image

import warpcloth as wc
from warpcloth.io.load import load_recording
from warpcloth.io.measured import read_encoder, read_laser_trace, read_measurement, read_tracked_shapes
from warpcloth.viz.plots import plot_run, plot_sweep, read_sweep_summary

SWING = overrides(run__duration_s=0.6, release__settle_time_s=0.1)


@pytest.fixture(scope="module")
def swing_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("swing")
    wc.simulate(wc.load_scene("damped_swing", SWING), out=out)
    return out


def pixels(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


def assert_not_blank(path):
    image = pixels(path)
    assert image.shape[0] > 200 and image.shape[1] > 200
    assert image.std() > 5  # more than a flat background
    assert (image.min(axis=2) < 200).mean() > 0.005  # some ink


def test_run_figures_are_written_and_show_the_swing(swing_run, tmp_path):
    recording = load_recording(swing_run)
    t, x = recording.probe("laser_x", 0)
    measured = tmp_path / "laser.csv"
    # A user's file: header, mm, every 5th sample, a little noise.
    rng = np.random.default_rng(1)
    rows = [f"{ti:.5f},{xi * 1e3 + rng.normal(0, 0.2):.4f}" for ti, xi in zip(t[::5], x[::5], strict=True)]
    measured.write_text("t_s,x_mm\n" + "\n".join(rows) + "\n")
    series = read_laser_trace(measured)
    np.testing.assert_allclose(series.x, x[::5], atol=1e-3)
    paths = plot_run(recording, tmp_path / "fig", measured=measured, times=np.array([0.0, 0.25, 0.5]))
    assert [p.name for p in paths] == ["amplitude.png", "clamp_angle.png", "shapes.png", "bending_loop.png",
                                       "energy.png"]
    for path in paths:
        assert_not_blank(path)


@pytest.mark.parametrize("reader, text, message", [
    (read_laser_trace, "t,x\n0.0,1.0\n", "at least two rows"),
    (read_laser_trace, "0.0,1.0\n0.1,abc\n", "line 2: could not convert"),
    (read_laser_trace, "0.0,1.0\n0.0,2.0\n", "data row 2 has t = 0 after 0"),
    (read_laser_trace, "0.0,1.0\n0.1,nan\n", "data row 2 is not finite"),
    (read_laser_trace, "0.0\n0.1\n", "line 1: expected 2 columns"),
    (read_measurement, "0 0 0\n1 1 1\n", "has 3 columns"),
    (read_tracked_shapes, "1,0.1,0,0,0\n0,0.0,0,0,0\n", "ordered by frame"),
    (read_tracked_shapes, "0,0.0,-5,0,0\n1,0.1,0,0,0\n", "s must be ≥ 0"),
    (read_encoder, "t,theta\n0.1,0\n0.05,1\n", "times must increase"),
])
def test_bad_measured_files_are_named(tmp_path, reader, text, message):
    path = tmp_path / "m.csv"
    path.write_text(text)
    with pytest.raises(wc.SceneError, match=message):
        reader(path)


def test_measured_forms_and_units(tmp_path):
    path = tmp_path / "enc.csv"
    path.write_text("t_s;theta_deg\n0;0\n0.1;90\n")
    np.testing.assert_allclose(read_encoder(path)[1], [0, np.pi / 2])
    path.write_text("# encoder\n0 0\n0.1 1.5\n")
    np.testing.assert_allclose(read_encoder(path)[1], [0, 1.5])
    path.write_text("t (s), theta (deg)\n0, 0\n0.1, 90\n")  # units in brackets, spaces
    np.testing.assert_allclose(read_encoder(path)[1], [0, np.pi / 2])
    path.write_bytes("0.0,1.0\n0.1,2.0\n0.2,3.0\n".encode("utf-8-sig"))  # a spreadsheet's byte-order mark
    assert len(read_laser_trace(path).t) == 3
    path.write_text("frame,t_s,s_mm,x_mm,y_mm\n0,0,10,1,-10\n0,0,20,2,-20\n1,0.0167,10,1.5,-10\n")
    shapes = read_measurement(path)
    np.testing.assert_allclose(shapes.s, [0.01, 0.02, 0.01])
    assert list(shapes.frame) == [0, 0, 1]


def test_sweep_metric_plots(tmp_path):
    sweep = wc.expand({"run": {"duration_s": 0.6}, "release": {"settle_time_s": 0.1},
                       "sweep": {"grid": {"damping.gamma_per_s": [0.1, 1.0, 3.0],
                                          "material.hysteresis_d1_gf_cm_per_cm": [0.0, 0.04]}}})
    wc.run_sweep(sweep, tmp_path / "sweep", workers=0, progress=False)
    summary = read_sweep_summary(tmp_path / "sweep")
    line = plot_sweep(summary, tmp_path / "line.png", "first_amplitude_m", "damping.gamma_per_s")
    heat = plot_sweep(summary, tmp_path / "heat.png", "first_amplitude_m", "damping.gamma_per_s",
                      "material.hysteresis_d1_gf_cm_per_cm")
    assert_not_blank(line)
    assert_not_blank(heat)
    with pytest.raises(wc.SceneError, match="--metric"):
        plot_sweep(summary, tmp_path / "bad.png", "no_such_metric", "damping.gamma_per_s")


def ribbon_columns(image):
    """Mean column of the strip's pixels (coloured: green above red, not the grey clamp)."""
    coloured = (image[..., 1] - image[..., 0] > 30) & (image.max(axis=2) < 250)
    return np.nonzero(coloured)[1].mean(), coloured.sum()


def test_render_draws_the_strip_where_it_is(swing_run, tmp_path):
    from warpcloth.viz.render import render_run

    recording = load_recording(swing_run)
    # The free end is held at x = +50 mm and released; a quarter period later it is
    # near the middle, half a period later on the far side (tip_x < 0).
    tip = recording.frames[:, 0, -1, 0]
    far = int(np.argmin(tip))
    assert tip[0] > 0.04 and tip[far] < -0.02
    paths = render_run(recording, tmp_path / "render", times=recording.frame_times[[0, far]], movie="motion.gif",
                       stride=3)
    assert [p.suffix for p in paths] == [".png", ".png", ".gif"]
    start, start_count = ribbon_columns(pixels(paths[0]))
    end, end_count = ribbon_columns(pixels(paths[1]))
    assert start_count > 1000 and end_count > 1000
    assert end < start - 50  # moved left on screen, as x decreased
    gif = Image.open(paths[2])
    assert gif.n_frames == len(range(0, len(recording.frame_times), 3))


def test_cli_export_plot_and_render(swing_run, tmp_path):
    def cli(*args):
        return subprocess.run([sys.executable, "-m", "warpcloth.cli", *args], capture_output=True, text=True,
                              timeout=300)

    done = cli("export-usd", str(swing_run), "-o", str(tmp_path / "swing.usdc"), "--ribbon")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "swing.usdc").is_file()
    done = cli("plot", str(swing_run), "--out", str(tmp_path / "fig"))
    assert done.returncode == 0, done.stderr
    assert len(list((tmp_path / "fig").glob("*.png"))) == 5
    done = cli("render", str(swing_run), "--out", str(tmp_path / "r"), "--times", "0.1", "--movie", "none")
    assert done.returncode == 0, done.stderr
    assert [p.name for p in (tmp_path / "r").iterdir()] == ["frame_00006.png"]
    done = cli("export-usd", str(swing_run), "-o", str(tmp_path / "x.obj"))
    assert done.returncode == 2 and "-o" in done.stderr and "x.obj" in done.stderr
    done = cli("render", str(swing_run), "--times", "9")
    assert done.returncode == 2 and "--times" in done.stderr
