"""Figures and renders, headless: files exist, are not blank, and show the strip where
the simulation put it."""

import re

import numpy as np
import pytest
from conftest import overrides, run_cli
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
    assert [p.name for p in paths] == [  # no clamp angle: the swing's clamp is fixed (θ = 0 throughout)
        "amplitude.png",
        "shapes.png",
        "bending_loop.png",
        "energy.png",
    ]
    for path in paths:
        assert_not_blank(path)


@pytest.mark.parametrize(
    "reader, text, message",
    [
        (read_laser_trace, "t,x\n0.0,1.0\n", "m.csv: expected at least two rows of laser trace"),
        (read_laser_trace, "0.0,1.0\n0.1,abc\n", "m.csv, line 2: 'abc' is not a number"),
        (read_laser_trace, "0.0,1.0\n0.0,2.0\n", r"m.csv, line 2: times must increase; t = 0 after 0 \(line 1\)"),
        (read_laser_trace, "0.0,1.0\n0.1,nan\n", "m.csv, line 2: x_mm is nan; every value must be finite"),
        (read_laser_trace, "0.0\n0.1\n", "m.csv, line 1: expected 2 columns, got 1"),
        (read_measurement, "0 0 0\n1 1 1\n", "m.csv, line 1: has 3 columns"),
        (
            read_tracked_shapes,
            "1,0.1,0,0,0\n0,0.0,0,0,0\n",
            r"m.csv, line 2: frame 0 at t = 0 s after frame 1 at t = 0.1 s \(line 1\): rows must be ordered by frame",
        ),
        (read_tracked_shapes, "0,0.0,-5,0,0\n1,0.1,0,0,0\n", "m.csv, line 1: arc length s must be ≥ 0"),
        (read_encoder, "t,theta\n0.1,0\n0.05,1\n", "m.csv, line 3: times must increase"),
    ],
)
def test_bad_measured_files_are_named(tmp_path, reader, text, message):
    path = tmp_path / "m.csv"
    path.write_text(text)
    with pytest.raises(wc.DataFileError, match=message):
        reader(path)


def test_measured_file_options_are_named(tmp_path):
    # A file that cannot be read blames the argument that named it; a bad angle_unit too.
    with pytest.raises(wc.ArgumentError, match="path: cannot read the laser trace file .*nope.csv"):
        read_laser_trace(tmp_path / "nope.csv")
    path = tmp_path / "enc.csv"
    path.write_text("0,0\n0.1,1\n")
    with pytest.raises(wc.ArgumentError, match="angle_unit: must be rad or deg, got 'grad'"):
        read_encoder(path, "grad")


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


# One reader (warpcloth.io.csv) for every instrument file: the measured-motion readers
# and the KES readers read the same file the same way.

T_PERCENT = np.array([0.0, 0.5, 1.25, 2.0, 3.0, 4.5, 6.0])  # a laser trace's t, or a loop's strain in %
X_FORCE = np.array([-0.75, 2.5, 31.0, 62.25, 110.5, 240.0, 500.0])  # x in mm, or force in gf/cm


def numbers(delimiter, decimal=".", fmt="{:.4f}"):
    return "".join(
        f"{fmt.format(a).replace('.', decimal)}{delimiter}{fmt.format(b).replace('.', decimal)}\n"
        for a, b in zip(T_PERCENT, X_FORCE, strict=True)
    )


def read_both(path):
    """The file as a laser trace and as a KES-FB1 loop."""
    from warpcloth.calibrate import kes

    return read_laser_trace(path), kes.read_tensile_csv(path)


@pytest.mark.parametrize(
    "name, text",
    [
        ("semicolon.csv", "# exported with decimal commas\n\n" + numbers(";", ",")),
        ("semicolon_trailing.csv", numbers(";", ",").replace("\n", ";\n")),  # a spreadsheet's trailing delimiter
        ("tab.txt", numbers("\t")),
        ("tab_comma.txt", numbers("\t", ",")),  # decimal commas: no number in the file has a point
        ("spaces_comma.txt", numbers("   ", ",")),
    ],
)
def test_every_reader_reads_a_delimiter_the_same(tmp_path, name, text):
    # Before one reader, the laser-trace reader split "0,5000;2,5000" at the commas too,
    # into t = 0, x = 5000 mm. Every form here reads exactly as the plain comma file.
    plain = tmp_path / "plain.csv"
    plain.write_text(numbers(","))
    path = tmp_path / name
    path.write_text(text)
    (trace, loop), (plain_trace, plain_loop) = read_both(path), read_both(plain)
    np.testing.assert_array_equal(plain_trace.t, T_PERCENT)
    np.testing.assert_array_equal(plain_trace.x, X_FORCE * 1e-3)
    np.testing.assert_array_equal(plain_loop.strain, T_PERCENT * 1e-2)
    np.testing.assert_array_equal(plain_loop.force, X_FORCE)
    for a, b in (
        (trace.t, plain_trace.t),
        (trace.x, plain_trace.x),
        (loop.strain, plain_loop.strain),
        (loop.force, plain_loop.force),
    ):
        np.testing.assert_array_equal(a, b, err_msg=name)
    assert list(loop.rows) == list(plain_loop.rows + (2 if name == "semicolon.csv" else 0))  # file lines


def test_tab_separated_names_with_spaces_are_read_by_every_reader(tmp_path):
    from warpcloth.calibrate import kes

    path = tmp_path / "tab.txt"
    path.write_text("Strain (%)\tForce (gf/cm)\n" + numbers("\t", ","))
    loop = kes.read_tensile_csv(path)
    np.testing.assert_array_equal(loop.force, X_FORCE)
    # as a laser trace its units are no time and length: refused, never read as s and mm
    with pytest.raises(wc.DataFileError, match=r"column 1 is headed 'Strain \(%\)': '%' is not a time unit"):
        read_laser_trace(path)
    path.write_text("time of day\tlaser x\n" + numbers("\t", ","))
    np.testing.assert_array_equal(read_laser_trace(path).t, T_PERCENT)
    assert loop.strain_unit == "strain in percent (from the header)"
    assert list(loop.rows) == list(range(2, 2 + len(T_PERCENT)))
    path.write_text("t (s)\ttheta (deg)\n0\t0\n0,1\t90\n")
    np.testing.assert_allclose(read_encoder(path)[1], [0, np.pi / 2])


@pytest.mark.parametrize(
    "torn, message",
    [
        ("2,0;62,25\n3,0;110,5\n4,5", "line 7: expected 2 columns, got 1: '4,5'"),  # a torn last line
        ("2,0;62,25\n3,0;1x0,5\n", "line 6: '1x0,5' is not a number"),
        ("2,0;62,25\n;110,5\n", "line 6: column 1 is empty"),
        ("2,0;62,25\n3,0;inf\n", "line 6: {x} is inf; every value must be finite"),
    ],
)
def test_a_torn_or_non_numeric_cell_is_named_with_its_line_by_every_reader(tmp_path, torn, message):
    from warpcloth.calibrate import kes

    path = tmp_path / "torn.csv"
    path.write_text("# a comment\n\nt;x\n0,0;-0,75\n" + torn)  # lines 1-3: comment, blank, header
    second = {
        read_laser_trace: "x_mm",
        read_measurement: "column 2",
        kes.read_tensile_csv: "force",
        read_encoder: "theta",
    }
    for read, x in second.items():
        with pytest.raises(wc.DataFileError, match=f"torn.csv, {re.escape(message.format(x=x))}"):
            read(path)


def test_an_ambiguous_decimal_comma_is_refused_naming_the_lines(tmp_path):
    path = tmp_path / "mixed.txt"
    path.write_text("t\tx\n0\t1.5\n0,1\t2\n")
    with pytest.raises(wc.DataFileError, match=r"mixed.txt, line 3: a decimal comma, but line 2 has a decimal point"):
        read_laser_trace(path)


def test_sweep_metric_plots(tmp_path):
    sweep = wc.expand(
        {
            "run": {"duration_s": 0.6},
            "release": {"enabled": True, "settle_time_s": 0.1},
            "sweep": {
                "grid": {"damping.gamma_per_s": [0.1, 1.0, 3.0], "material.hysteresis_d1_gf_cm_per_cm": [0.0, 0.04]}
            },
        }
    )
    summary = wc.run_sweep(sweep, tmp_path / "sweep", workers=0, progress=False)
    assert np.isfinite(summary["first_amplitude_m"]).all()  # real swings, not rounding
    summary = read_sweep_summary(tmp_path / "sweep")
    line = plot_sweep(summary, tmp_path / "line.png", "first_amplitude_m", "damping.gamma_per_s")
    heat = plot_sweep(
        summary,
        tmp_path / "heat.png",
        "first_amplitude_m",
        "damping.gamma_per_s",
        "material.hysteresis_d1_gf_cm_per_cm",
    )
    assert_not_blank(line)
    assert_not_blank(heat)
    with pytest.raises(wc.ArgumentError, match="metric: .no_such_metric. is not a column of the sweep summary"):
        plot_sweep(summary, tmp_path / "bad.png", "no_such_metric", "damping.gamma_per_s")
    # --where and --variants choose the variants drawn (issue 39: they were ignored, and a
    # selection that matched nothing drew every variant)
    metric = ("--metric", "first_amplitude_m", "--x", "damping.gamma_per_s")
    done = run_cli(
        "plot", str(tmp_path / "sweep"), *metric, "--where", "damping.gamma_per_s<2", "--out", str(tmp_path / "w")
    )
    assert done.returncode == 0 and "(4 of the variants)" in done.stdout, done.stderr
    done = run_cli("plot", str(tmp_path / "sweep"), *metric, "--variants", "0,5", "--out", str(tmp_path / "v"))
    assert done.returncode == 0 and "(2 of the variants)" in done.stdout, done.stderr
    for selection, words in (
        (("--where", "damping.gamma_per_s<0"), "--where: 'damping.gamma_per_s<0' matches no variant"),
        (("--variants", "7"), "--variants: variant 7 does not exist (there are 6)"),
    ):
        done = run_cli("plot", str(tmp_path / "sweep"), *metric, *selection, "--out", str(tmp_path / "none"))
        assert done.returncode == 2 and words in done.stderr, done.stderr
        assert not (tmp_path / "none").exists()


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
    paths = render_run(
        recording, tmp_path / "render", times=recording.frame_times[[0, far]], movie="motion.gif", stride=3
    )
    assert [p.suffix for p in paths] == [".png", ".png", ".gif"]
    start, start_count = ribbon_columns(pixels(paths[0]))
    end, end_count = ribbon_columns(pixels(paths[1]))
    assert start_count > 1000 and end_count > 1000
    assert end < start - 50  # moved left on screen, as x decreased
    gif = Image.open(paths[2])
    assert gif.n_frames == len(range(0, len(recording.frame_times), 3))
    durations = []
    for k in range(gif.n_frames):
        gif.seek(k)
        durations.append(gif.info["duration"])
    # real time: 3 frames of 1/60 s each in a whole 5 cs (browsers slow anything under 2 cs to 10 cs)
    assert set(durations) == {50} and sum(durations) / 1e3 == pytest.approx(gif.n_frames * 3 / 60)


def test_gif_strides_play_in_real_time():
    from warpcloth.viz.render import gif_stride

    for rate in (60.0, 50.0, 30.0, 600.0, 24.0, 100.0):
        k = gif_stride(rate)
        delay = 100 * k / rate
        assert delay >= 2 and delay == pytest.approx(round(delay)), rate
    assert gif_stride(60.0) == 3 and gif_stride(60.0, stride=4) == 6


def test_cli_export_plot_and_render(swing_run, tmp_path):
    def cli(*args):
        return run_cli(*args)

    done = cli("export-usd", str(swing_run), "-o", str(tmp_path / "swing.usdc"), "--ribbon")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "swing.usdc").is_file()
    done = cli("plot", str(swing_run), "--out", str(tmp_path / "fig"))
    assert done.returncode == 0, done.stderr
    assert len(list((tmp_path / "fig").glob("*.png"))) == 4  # no clamp angle: the swing's clamp is fixed
    done = cli("render", str(swing_run), "--out", str(tmp_path / "r"), "--times", "0.1", "--movie", "none")
    assert done.returncode == 0, done.stderr
    assert [p.name for p in (tmp_path / "r").iterdir()] == ["frame_00006.png"]
    done = cli("export-usd", str(swing_run), "-o", str(tmp_path / "x.obj"))
    assert done.returncode == 2 and "-o" in done.stderr and "x.obj" in done.stderr
    done = cli("render", str(swing_run), "--times", "9")
    assert done.returncode == 2 and "--times" in done.stderr


def test_a_sampled_sweep_is_plotted_as_points_not_a_zigzag():
    # Latin-hypercube samples: every x value is unique while other fields vary, so the
    # points are scattered (coloured by another swept field), never joined in x order.
    import matplotlib.pyplot as plt
    import pandas as pd

    from warpcloth.viz.plots import sweep_figure

    rng = np.random.default_rng(0)
    summary = pd.DataFrame(
        {
            "variant": range(30),
            "damping.gamma_per_s": rng.random(30),
            "material.hysteresis_d1_gf_cm_per_cm": rng.random(30),
            "first_period_s": rng.random(30),
            "diverged": False,
        }
    )
    figure = sweep_figure(summary, "first_period_s", "damping.gamma_per_s")
    axes = figure.axes
    assert not any(len(line.get_xdata()) > 1 for line in axes[0].get_lines())  # nothing joined
    assert len(axes) == 2 and axes[1].get_ylabel() == "D1 (gf·cm/cm)"  # the colourbar, symbol and unit
    assert axes[0].get_xlabel() == "γ (s⁻¹)" and axes[0].get_ylabel() == "first period (s)"
    plt.close(figure)
    one_d = sweep_figure(
        summary[["variant", "damping.gamma_per_s", "first_period_s", "diverged"]],
        "first_period_s",
        "damping.gamma_per_s",
    )
    assert len(one_d.axes[0].get_lines()[0].get_xdata()) == 30  # a 1-D sweep is still a curve
    plt.close(one_d)


@pytest.fixture()
def figures(monkeypatch):
    """The figures the plot functions save, by file name, kept open for inspection."""
    from warpcloth.viz.figures import common

    saved = {}

    def keep(fig, path, dpi=common.DPI):
        saved[path.name] = fig
        return path

    monkeypatch.setattr(common, "save", keep)
    yield saved
    import matplotlib.pyplot as plt

    plt.close("all")


def test_measured_files_go_onto_the_figure_of_their_kind(swing_run, tmp_path, figures):
    recording = load_recording(swing_run)
    t, x = recording.probe("laser_x", 0)
    laser, encoder, shapes = tmp_path / "laser.csv", tmp_path / "encoder.csv", tmp_path / "markers.csv"
    laser.write_text("t_s,x_mm\n" + "".join(f"{a:.5f},{b * 1e3:.4f}\n" for a, b in zip(t[::20], x[::20], strict=True)))
    encoder.write_text("t_s,theta_deg\n0,0\n0.1,0.5\n0.2,1.0\n")
    frames = recording.frames
    nc = recording.n_clamped
    rows = [
        f"{f},{recording.frame_times[f]:.5f},{10 * k},{frames[f, 0, nc - 1 + 2 * k, 0] * 1e3:.4f},"
        f"{frames[f, 0, nc - 1 + 2 * k, 1] * 1e3:.4f}\n"
        for f in (3, 9, 15)
        for k in range(1, 4)
    ]
    shapes.write_text("frame,t_s,s_mm,x_mm,y_mm\n" + "".join(rows))

    def labels(name):
        return [line.get_label() for ax in figures[name].axes for line in ax.get_lines()]

    plot_run(recording, tmp_path / "a", measured=laser)
    assert "measured" in labels("amplitude.png") and "clamp_angle.png" not in figures  # a fixed clamp
    plot_run(recording, tmp_path / "b", measured=encoder)
    assert "encoder (measured)" in labels("clamp_angle.png") and "measured" not in labels("amplitude.png")
    drawn = figures["clamp_angle.png"].axes[0].get_lines()[-1]
    np.testing.assert_allclose(drawn.get_ydata(), [0, 0.5, 1.0])  # degrees, as the file says
    plot_run(recording, tmp_path / "c", measured=shapes)
    ax = figures["shapes.png"].axes[0]
    markers = [line for line in ax.get_lines() if line.get_marker() == "o"]
    assert len(markers) == 3  # one set per measured frame, over the strip at that frame
    for line, f in zip(markers, (3, 9, 15), strict=True):
        np.testing.assert_allclose(line.get_xdata(), frames[f, 0, nc + 1 : nc + 6 : 2, 0] * 1e3, atol=1e-3)
    # The simulated shapes are drawn at the measured frames (origin: the clamp edge, as the markers)
    drawn_at = [line.get_label() for line in ax.get_lines() if line.get_label().endswith(" s")]
    assert drawn_at == [f"{recording.frame_times[f]:.3f} s" for f in (3, 9, 15)]


def test_an_encoder_is_refused_where_a_motion_of_the_strip_is_expected(tmp_path):
    from warpcloth.errors import DataFileError

    path = tmp_path / "enc.csv"
    path.write_text("t_s,theta_deg\n0,0\n0.1,0.5\n")
    with pytest.raises(DataFileError, match=r"enc.csv, line 1: is a clamp encoder .*'theta_deg'.*clamp fit-angle"):
        read_measurement(path)
    assert read_measurement(path, encoder=True).theta[1] == pytest.approx(np.radians(0.5))
    path.write_text("t (s), angle [rad]\n0, 0\n0.1, 0.5\n")
    assert read_measurement(path, encoder=True).theta[1] == pytest.approx(0.5)
    path.write_text("t_s,x_mm\n0,0\n0.1,0.5\n")  # a laser trace stays one
    assert read_measurement(path, encoder=True).x[1] == pytest.approx(0.5e-3)


def test_default_shapes_show_the_first_half_swing_with_the_laser_line(swing_run, figures, tmp_path):
    from warpcloth.metrics import extrema
    from warpcloth.viz.plots import default_shape_times

    recording = load_recording(swing_run)
    times = default_shape_times(recording)
    t, tip = recording.probe("tip_x", 0)
    # released at rest on one side (t = 0), it reaches the far side half a period later
    assert times[0] == 0.0 and len(times) == 9
    far_side = t[np.argmin(tip[t < 0.4])]
    assert abs(times[-1] - far_side) < 2 / 600 and 0.2 < times[-1] < 0.32
    assert extrema(t, tip, starts_at_rest=True)[0][1] == pytest.approx(times[-1], abs=2e-3)
    plot_run(recording, tmp_path / "f")
    ax = figures["shapes.png"].axes[0]
    laser = [line for line in ax.get_lines() if line.get_label().startswith("laser line")]
    assert len(laser) == 1 and laser[0].get_ydata()[0] == recording.scenes[0].output.laser_height_mm
    assert ax.get_xlabel() == "x from the clamp edge (mm)"


def test_the_bending_loop_is_zoomed_to_the_path_and_marks_kes_b_and_2hb(swing_run, figures, tmp_path):
    from warpcloth import units
    from warpcloth.calibrate.kes import BendingLoop, bending_summary
    from warpcloth.cli.view import material_kes_values
    from warpcloth.viz.plots import kes_loop

    recording = load_recording(swing_run)
    kes = material_kes_values(recording)
    plot_run(recording, tmp_path / "f", kes=kes)
    chart, zoom = figures["bending_loop.png"].axes
    legend = [text.get_text() for text in chart.get_legend().get_texts()]
    assert f"B = {kes.b_gf_cm2_per_cm:.4g} gf·cm²/cm (slope, 0.5–1.5)" in legend
    assert f"2HB = {kes.hb2_gf_cm_per_cm:.4g} gf·cm/cm (width at K = 1)" in legend
    # B and 2HB are the KES reading of the material's own loop; for the centred loop of
    # the paper's law 2HB = 2 M0 − D1 (e^{−α(K0+1)} + e^{−α(K0−1)}), M0 = ½ D1 (1 + e^{−2αK0})
    # (docs/model.md §4.2, K in 1/cm), and B is D up to the branches' curvature there
    material = recording.scenes[0].material
    d1, alpha, k0 = (material.hysteresis_d1_gf_cm_per_cm, material.hysteresis_alpha_cm, material.hysteresis_k0_per_cm)
    m0 = 0.5 * d1 * (1 + np.exp(-2 * alpha * k0))
    assert kes.hb2_gf_cm_per_cm == pytest.approx(
        2 * m0 - d1 * (np.exp(-alpha * (k0 + 1)) + np.exp(-alpha * (k0 - 1))), rel=2e-3
    )
    assert kes.b_gf_cm2_per_cm == pytest.approx(material.bending_rigidity_gf_cm2_per_cm, rel=0.01)
    k, m = kes_loop(recording)
    assert kes == bending_summary(
        BendingLoop(k / units.CURVATURE_PER_CM, m / units.MOMENT_GF_CM_PER_CM, np.arange(1, len(k) + 1), "x")
    )
    _, curvature = recording.probe("loop_curvature", 0)
    path = curvature / units.CURVATURE_PER_CM
    lo, hi = zoom.get_xlim()
    assert lo <= path.min() and hi >= path.max()  # the whole path shows
    assert hi - lo < 1.2 * np.ptp(path)  # and fills the axes, not the ±K0 frame
    assert chart.get_xlim()[1] > k.max() / units.CURVATURE_PER_CM  # the chart shows the whole loop


def test_the_energy_figure_shows_the_drift_in_percent_of_peak_kinetic(swing_run, figures, tmp_path):
    recording = load_recording(swing_run)
    plot_run(recording, tmp_path / "f")
    top, drift = figures["energy.png"].axes
    assert drift.get_ylabel() == "sum − start\n(% of peak kinetic)"
    total = top.get_lines()[-1].get_ydata() * 1e-6
    peak = recording.probe("kinetic", 0)[1].max()
    np.testing.assert_allclose(drift.get_lines()[0].get_ydata(), 100 * (total - total[0]) / peak, atol=1e-9)
    assert np.abs(drift.get_lines()[0].get_ydata()).max() < 1.0  # the budget closes to < 1 % of peak KE


def test_formats_and_dpi(swing_run, tmp_path):
    recording = load_recording(swing_run)
    small = plot_run(recording, tmp_path / "small", dpi=60)
    large = plot_run(recording, tmp_path / "large", dpi=120)
    for a, b in zip(small, large, strict=True):
        assert Image.open(b).size[0] == pytest.approx(2 * Image.open(a).size[0], abs=2)
    svg = plot_run(recording, tmp_path / "svg", fmt="svg")  # a fixed clamp: no clamp-angle figure
    assert [p.suffix for p in svg] == [".svg"] * 4 and svg[0].read_text().lstrip().startswith("<?xml")
    pdf = plot_run(recording, tmp_path / "pdf", fmt="pdf")
    assert all(p.read_bytes().startswith(b"%PDF") for p in pdf)
    with pytest.raises(wc.ArgumentError, match="fmt: must be one of png, pdf, svg, got 'jpg'"):
        plot_run(recording, tmp_path / "x", fmt="jpg")
    with pytest.raises(wc.ArgumentError, match="dpi: must be between 10 and 2400, got 1"):
        plot_run(recording, tmp_path / "x", dpi=1)


def test_many_variants_are_coloured_by_a_parameter_not_listed_in_a_legend(tmp_path, figures):
    gammas = np.linspace(0.1, 1.2, 12)
    scenes = [
        wc.load_scene("damped_swing", {"run.duration_s": 0.05, "release.settle_time_s": 0.05, "damping.gamma_per_s": g})
        for g in gammas
    ]
    wc.simulate(scenes, out=tmp_path / "run")
    plot_run(load_recording(tmp_path / "run"), tmp_path / "f")
    ax, colourbar = figures["amplitude.png"].axes  # (the swing's fixed clamp has no clamp-angle figure)
    assert ax.get_legend() is None and colourbar.get_ylabel() == "γ (s⁻¹)"
    lines = ax.get_lines()[:12]
    # the variant with the largest γ is drawn in viridis' last colour
    assert np.allclose(lines[-1].get_color(), plt_viridis(1.0)) and np.allclose(lines[0].get_color(), plt_viridis(0.0))


def plt_viridis(x):
    import matplotlib.pyplot as plt

    return plt.cm.viridis(x)


def test_a_metric_no_variant_has_is_refused_not_drawn_empty():
    import pandas as pd

    from warpcloth.errors import ArgumentError
    from warpcloth.viz.plots import sweep_figure

    summary = pd.DataFrame(
        {
            "variant": range(4),
            "damping.gamma_per_s": [0.1, 0.2, 0.1, 0.2],
            "material.bending_rigidity_gf_cm2_per_cm": [0.1, 0.1, 0.2, 0.2],
            "first_period_s": np.nan,
            "mean_log_decrement": [0.1, np.nan, 0.3, 0.4],
            "diverged": False,
        }
    )
    with pytest.raises(ArgumentError, match="metric: no variant has a value of 'first_period_s'"):
        sweep_figure(summary, "first_period_s", "damping.gamma_per_s", "material.bending_rigidity_gf_cm2_per_cm")
    figure = sweep_figure(summary, "mean_log_decrement", "damping.gamma_per_s")
    assert figure.axes[0].get_title() == "mean log decrement per half-cycle over 3 variants (1 without a value)"


def test_a_grid_over_the_bending_law_draws_a_line_per_law():
    import pandas as pd

    from warpcloth.viz.plots import sweep_figure

    laws = ["tagawa2003", "dahl", "frictional_couple"]
    summary = pd.DataFrame(
        {
            "variant": range(9),
            "material.bending_law": np.repeat(laws, 3),
            "damping.gamma_per_s": np.tile([0.2, 0.5, 0.8], 3),
            "mean_log_decrement": np.arange(9) / 10,
            "diverged": False,
        }
    )
    ax = sweep_figure(summary, "mean_log_decrement", "damping.gamma_per_s").axes[0]
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == [f"bending law = {law}" for law in laws]
    np.testing.assert_array_equal(lines[2].get_ydata(), [0.6, 0.7, 0.8])
    heat = sweep_figure(summary, "mean_log_decrement", "damping.gamma_per_s", "material.bending_law")
    assert heat.axes[0].get_ylabel() == "bending law"


def test_one_origin_the_clamp_edge_in_scenes_results_and_files(swing_run, tmp_path):
    import json
    import shutil

    from warpcloth.errors import DataFileError

    recording = load_recording(swing_run)
    scene, nc = recording.scenes[0], recording.n_clamped
    # at rest (the first frame holds the clamp still) the clamp-edge node is the origin and
    # the clamp reaches up to y = L_c; the laser line is where the scene's offset says
    assert np.array_equal(recording.frames[0, 0, nc - 1], [0.0, 0.0])
    assert recording.frames[0, 0, 0, 1] == pytest.approx(scene.strip.clamp_length_mm * 1e-3)
    t, laser = recording.probe("laser_x", 0)
    frames_at = recording.nearest_frames(t[:1])
    xy = recording.frames[frames_at[0], 0]
    below = np.flatnonzero(xy[:, 1] <= scene.output.laser_height_mm * 1e-3)[0]
    a, b = xy[below - 1], xy[below]
    crossing = a[0] + (b[0] - a[0]) * (scene.output.laser_height_mm * 1e-3 - a[1]) / (b[1] - a[1])
    assert laser[0] == pytest.approx(crossing, abs=1e-9)
    meta = json.loads((swing_run / "meta.json").read_text())
    assert "clamp edge" in meta["coordinates"]
    # a run from before (positions from the clamp's top) is refused, not shown 20 mm off
    old = tmp_path / "old"
    shutil.copytree(swing_run, old)
    meta.pop("coordinates")
    (old / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(DataFileError, match="does not say its positions are from the clamp edge"):
        load_recording(old)


def test_a_text_column_is_refused_as_a_metric():
    import pandas as pd

    from warpcloth.errors import ArgumentError
    from warpcloth.viz.plots import sweep_figure

    summary = pd.DataFrame(
        {
            "variant": range(3),
            "damping.gamma_per_s": [0.1, 0.2, 0.3],
            "diverged_phase": ["", "", ""],
            "first_period_s": [0.5, 0.5, 0.5],
            "diverged": False,
        }
    )
    with pytest.raises(ArgumentError, match="metric: 'diverged_phase' is not a number per variant"):
        sweep_figure(summary, "diverged_phase", "damping.gamma_per_s")


def test_many_variants_differing_by_a_choice_are_coloured_by_it(tmp_path, figures):
    # 9 variants whose only difference is the bending law: colours follow the laws'
    # order (as renders and USD colour them), no legend, and no float conversion of a name
    laws = ["tagawa2003", "dahl", "frictional_couple"] * 3
    scenes = [
        wc.load_scene(
            "damped_swing", {"run.duration_s": 0.05, "release.settle_time_s": 0.05, "material.bending_law": law}
        )
        for law in laws
    ]
    wc.simulate(scenes, out=tmp_path / "run")
    plot_run(load_recording(tmp_path / "run"), tmp_path / "f")
    ax, colourbar = figures["amplitude.png"].axes
    assert ax.get_legend() is None and colourbar.get_ylabel() == "bending law"
    colours = [tuple(line.get_color()) for line in ax.get_lines()[:9]]
    assert colours[0] == colours[3] == colours[6] != colours[1]


def test_heat_map_ticks_sit_at_the_centres_of_the_grid_cells():
    # One cell per grid value, each tick at its cell's centre and labelled with the value;
    # before, the locator's round numbers (0.25, 0.5, ...) fell anywhere across the cells,
    # and on an uneven grid (0.1, 0.4, 0.7, 1.3) a cell's centre was not its value.
    import matplotlib.pyplot as plt
    import pandas as pd

    from warpcloth.viz.plots import HEAT_MAP_TICKS, sweep_figure

    gammas, d1s = [0.1, 0.4, 0.7, 1.3], [0.0, 0.025, 0.08]
    grid = pd.DataFrame([(g, d) for d in d1s for g in gammas], columns=["damping.gamma_per_s", D1_FIELD])
    summary = grid.assign(variant=range(len(grid)), first_period_s=np.arange(len(grid)) / 10, diverged=False)
    ax = sweep_figure(summary, "first_period_s", "damping.gamma_per_s", D1_FIELD).axes[0]
    coordinates = ax.collections[0].get_coordinates()
    for axis, values, k in ((ax.xaxis, gammas, 0), (ax.yaxis, d1s, 1)):
        edges = np.unique(coordinates[..., k])
        np.testing.assert_allclose(axis.get_ticklocs(), 0.5 * (edges[:-1] + edges[1:]))  # the cells' centres
        assert [t.get_text() for t in axis.get_ticklabels()] == [f"{v:.4g}" for v in values]
    cells = ax.collections[0].get_array().reshape(len(d1s), len(gammas))
    assert (
        cells[1, 2] == summary.query(f"`damping.gamma_per_s` == 0.7 and `{D1_FIELD}` == 0.025")["first_period_s"].item()
    )  # the cell labelled (0.7, 0.025) holds that variant
    plt.close("all")
    # a long grid labels every k-th cell, still at cell centres
    many = np.round(np.linspace(0.0, 2.9, 30), 3)
    wide = pd.DataFrame([(g, d) for d in d1s for g in many], columns=["damping.gamma_per_s", D1_FIELD])
    wide = wide.assign(variant=range(len(wide)), first_period_s=0.5, diverged=False)
    axis = sweep_figure(wide, "first_period_s", "damping.gamma_per_s", D1_FIELD).axes[0].xaxis
    ticks = axis.get_ticklocs()
    assert len(ticks) <= HEAT_MAP_TICKS and np.all(ticks == np.round(ticks)) and ticks[0] == 0
    assert [t.get_text() for t in axis.get_ticklabels()] == [f"{many[int(i)]:.4g}" for i in ticks]
    plt.close("all")


D1_FIELD = "material.hysteresis_d1_gf_cm_per_cm"


def test_a_driven_clamp_has_no_release_on_its_time_axes(swing_run, tmp_path, figures):
    # The impulsive rotation starts its clamp at t = 0 and has no release: its figures say t.
    wc.simulate(wc.load_scene("impulsive_rotation", {"run.duration_s": 0.1}), out=tmp_path / "rotation")
    plot_run(load_recording(tmp_path / "rotation"), tmp_path / "f")
    rotation = {name: fig for name, fig in figures.items()}
    texts = [t for fig in rotation.values() for ax in fig.axes for t in (ax.get_xlabel(), ax.get_ylabel())]
    texts += [
        ax.get_legend().get_title().get_text()
        for fig in rotation.values()
        for ax in fig.axes
        if ax.get_legend() is not None
    ]
    assert not [t for t in texts if "release" in t]
    assert rotation["amplitude.png"].axes[0].get_xlabel() == "t (s)"
    assert rotation["shapes.png"].axes[0].get_legend().get_title().get_text() == "t"
    figures.clear()
    plot_run(load_recording(swing_run), tmp_path / "g")  # the released swing keeps its release
    assert figures["amplitude.png"].axes[0].get_xlabel() == "t after release (s)"
    assert figures["shapes.png"].axes[0].get_legend().get_title().get_text() == "t after release"
    assert figures["energy.png"].axes[1].get_xlabel() == "t after release (s)"


def test_the_1_and_2_sigma_ellipses_have_their_own_legend_entries():
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from warpcloth.viz.plots import fit_search_figure

    names = ["damping.gamma_per_s", D1_FIELD]
    fit = SimpleNamespace(
        parameters=dict(zip(names, [0.55, 0.025], strict=True)),
        sigma=dict(zip(names, [0.002, 0.0002], strict=True)),
        correlation=[[1.0, 0.4], [0.4, 1.0]],
        history=[{names[0]: 0.3, names[1]: 0.04}, {names[0]: 0.55, names[1]: 0.025}],
    )
    figure = fit_search_figure(fit, dict(zip(names, [0.551, 0.0251], strict=True)))
    ax = figure.axes[0]
    entries = dict(zip(*reversed(ax.get_legend_handles_labels()), strict=True))
    assert {"1σ", "2σ"} <= set(entries)
    one, two = entries["1σ"], entries["2σ"]
    assert one.get_linestyle() != two.get_linestyle()  # told apart in the legend, not two identical lines
    # each ellipse reaches k σ along each parameter (its projection), so the 2σ one is twice the 1σ one
    for k, line in ((1, one), (2, two)):
        assert np.max(np.abs(line.get_xdata() - 0.55)) == pytest.approx(k * 0.002, rel=1e-3)
        assert np.max(np.abs(line.get_ydata() - 0.025)) == pytest.approx(k * 0.0002, rel=1e-3)
    assert ax.get_xlabel() == "γ (s⁻¹)" and ax.get_ylabel() == "D1 (gf·cm/cm)"
    plt.close(figure)


def test_the_marker_overlay_axes_read_as_the_shape_figures(swing_run, tmp_path, figures):
    from types import SimpleNamespace

    from warpcloth.viz.plots import plot_fit_overlay

    recording = load_recording(swing_run)
    nc = recording.n_clamped
    path = tmp_path / "markers.csv"
    path.write_text(
        "frame,t_s,s_mm,x_mm,y_mm\n"
        + "".join(
            f"{f},{recording.frame_times[f]:.5f},{10 * k},{recording.frames[f, 0, nc - 1 + 2 * k, 0] * 1e3:.4f},"
            f"{recording.frames[f, 0, nc - 1 + 2 * k, 1] * 1e3:.4f}\n"
            for f in (3, 9)
            for k in (1, 2)
        )
    )
    result = SimpleNamespace(frames=recording.frames, frame_times=recording.frame_times)
    fit = SimpleNamespace(
        shift_s=0.0, parameters={"damping.gamma_per_s": 0.3}, sigma={"damping.gamma_per_s": 0.01}, rms=1e-4
    )
    shapes = read_tracked_shapes(path)
    objective = SimpleNamespace(scene=recording.scenes[0], residuals=lambda *a, **k: np.zeros(2 * len(shapes.t)))
    plot_fit_overlay(result, objective, shapes, fit, tmp_path / "overlay.png")
    plot_run(recording, tmp_path / "f", measured=path)
    overlay, shapes = figures["overlay.png"].axes[0], figures["shapes.png"].axes[0]
    assert (
        (overlay.get_xlabel(), overlay.get_ylabel())
        == (shapes.get_xlabel(), shapes.get_ylabel())
        == ("x from the clamp edge (mm)", "y from the clamp edge (mm)")
    )


def test_a_measured_trace_and_the_run_are_drawn_on_one_window(swing_run, tmp_path, figures):
    # Issue 22: plot --measured draws the run only where the trace is (their overlap),
    # or on --from/--to, and says which in the title; a window outside is refused first.
    from warpcloth.errors import ArgumentError

    recording = load_recording(swing_run)
    t, x = recording.probe("laser_x", 0)
    half = t <= t[-1] / 2 + 1e-9
    laser = tmp_path / "laser.csv"
    laser.write_text("t_s,x_mm\n" + "".join(f"{a:.6f},{b * 1e3:.4f}\n" for a, b in zip(t[half], x[half], strict=True)))
    end = float(np.round(t[half][-1], 6))
    plot_run(recording, tmp_path / "a", measured=laser)
    ax = figures["amplitude.png"].axes[0]
    run_line = ax.get_lines()[0]
    assert run_line.get_xdata().max() == pytest.approx(end, abs=1e-6)
    assert f"compared on t = 0 … {end:g} s" in ax.get_title()
    plot_run(recording, tmp_path / "b", measured=laser, t_from=0.1, t_to=0.2)
    xs = figures["amplitude.png"].axes[0].get_lines()[0].get_xdata()
    assert xs.min() >= 0.1 - 1e-9 and xs.max() <= 0.2 + 1e-9
    with pytest.raises(ArgumentError, match=rf"t_to: 5 s is after the end of .*laser.csv \({end:g} s\)"):
        plot_run(recording, tmp_path / "c", measured=laser, t_to=5.0)
    assert not (tmp_path / "c").exists()
