"""Issue 40, the strips' part: every figure a strip's commands write is read as a figure
(its axes, labels and drawn data, and that its text stays on the page), and every fitted
value printed has its σ or says it is not determined."""

import io
import re
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import overrides, run_cli

import warpcloth as wc
from warpcloth.calibrate.clamp_fit import fit_clamp_motion, parameter_uncertainties
from warpcloth.io.load import load_recording
from warpcloth.io.measured import read_encoder, read_tracked_shapes
from warpcloth.viz.plots import plot_fit_overlay, plot_run


@pytest.fixture()
def figures(monkeypatch):
    """The figures the plot functions save, by file name, kept open (and drawn, so their
    text has a size) for inspection."""
    import matplotlib.pyplot as plt

    from warpcloth.viz.figures import common

    saved = {}

    def keep(fig, path, dpi=common.DPI):
        fig.tight_layout()
        fig.canvas.draw()
        saved[path.name] = fig
        return path

    monkeypatch.setattr(common, "save", keep)
    yield saved
    plt.close("all")


@pytest.fixture(scope="module")
def rotation(tmp_path_factory):
    out = tmp_path_factory.mktemp("rotation")
    wc.simulate(wc.load_scene("impulsive_rotation", {"run.duration_s": 0.1}), out=out)
    return out


@pytest.fixture(scope="module")
def swing(tmp_path_factory):
    out = tmp_path_factory.mktemp("swing")
    wc.simulate(wc.load_scene("damped_swing", overrides(run__duration_s=0.2, release__settle_time_s=0.1)), out=out)
    return out


def on_the_page(fig):
    """Every title and axis label lies within the figure (a title that runs off is cut)."""
    page = fig.bbox
    texts = [t for ax in fig.axes for t in (ax.title, ax.xaxis.label, ax.yaxis.label) if t.get_text()]
    texts += [t for t in fig.texts if t.get_text()]
    for text in texts:
        box = text.get_window_extent()
        assert page.x0 - 1 <= box.x0 and box.x1 <= page.x1 + 1, text.get_text()


def test_a_short_record_cuts_only_the_figure_that_draws_it(rotation, tmp_path, figures):
    recording = load_recording(rotation)
    t, x = recording.probe("laser_x", 0)
    short = t <= 0.05 + 1e-9
    laser = tmp_path / "laser.csv"
    rows = [f"{a:.6f},{b * 1e3:.4f}\n" for a, b in zip(t[short], x[short], strict=True)]
    laser.write_text("t_s,x_mm\n" + "".join(rows))
    plot_run(recording, tmp_path / "a", measured=laser)
    amplitude, angle = figures["amplitude.png"].axes[0], figures["clamp_angle.png"].axes[0]
    assert amplitude.get_lines()[0].get_xdata().max() == pytest.approx(0.05, abs=1e-6)
    assert "compared on t = 0 … 0.05 s" in amplitude.get_title()
    # the clamp angle does not draw the laser trace: the whole run, and its title says no window
    assert angle.get_lines()[0].get_xdata().max() == pytest.approx(t[-1], abs=1e-9)
    assert "compared" not in angle.get_title()
    for fig in figures.values():
        on_the_page(fig)
    # an encoder cuts the clamp angle, not the amplitude; --from/--to cut both
    encoder = tmp_path / "encoder.csv"
    encoder.write_text("t_s,theta_deg\n0,0\n0.02,1\n0.04,3\n")
    plot_run(recording, tmp_path / "b", measured=encoder)
    assert figures["clamp_angle.png"].axes[0].get_lines()[0].get_xdata().max() == pytest.approx(0.04, abs=1e-6)
    assert figures["amplitude.png"].axes[0].get_lines()[0].get_xdata().max() == pytest.approx(t[-1], abs=1e-9)
    plot_run(recording, tmp_path / "c", measured=encoder, t_from=0.01, t_to=0.03)
    for name in ("amplitude.png", "clamp_angle.png"):
        xs = figures[name].axes[0].get_lines()[0].get_xdata()
        assert xs.min() >= 0.01 - 1e-9 and xs.max() <= 0.03 + 1e-9


def test_a_fixed_clamp_gets_no_clamp_angle_figure_unless_an_encoder_is_drawn(swing, tmp_path, figures):
    recording = load_recording(swing)
    assert recording.scenes[0].clamp.motion == "fixed"
    names = [p.name for p in plot_run(recording, tmp_path / "a")]
    assert names == ["amplitude.png", "shapes.png", "bending_loop.png", "energy.png"]
    assert not (tmp_path / "a" / "clamp_angle.png").exists()
    encoder = tmp_path / "encoder.csv"
    encoder.write_text("t_s,theta_deg\n0,0\n0.1,0.1\n0.2,0.2\n")
    assert "clamp_angle.png" in [p.name for p in plot_run(recording, tmp_path / "b", measured=encoder)]
    labels = [line.get_label() for line in figures["clamp_angle.png"].axes[0].get_lines()]
    assert "encoder (measured)" in labels


def test_the_marker_overlay_has_a_residual_panel_per_coordinate(rotation, tmp_path, figures):
    recording = load_recording(rotation)
    nc = recording.n_clamped
    frames = (2, 4, 6)
    path = tmp_path / "markers.csv"
    path.write_text(
        "frame,t_s,s_mm,x_mm,y_mm\n"
        + "".join(
            f"{f},{recording.frame_times[f]:.5f},{10 * k},{recording.frames[f, 0, nc - 1 + 4 * k, 0] * 1e3:.4f},"
            f"{recording.frames[f, 0, nc - 1 + 4 * k, 1] * 1e3:.4f}\n"
            for f in frames
            for k in (1, 2, 3)
        )
    )
    shapes = read_tracked_shapes(path)
    residual = np.random.default_rng(3).normal(0, 1e-4, 2 * len(shapes.t))  # m, [row, xy] flattened
    objective = SimpleNamespace(scene=recording.scenes[0], residuals=lambda *a, **k: residual)
    result = SimpleNamespace(frames=recording.frames, frame_times=recording.frame_times)
    fit = SimpleNamespace(
        shift_s=0.0,
        parameters={"damping.gamma_per_s": 0.8, "clamp.rotation_centre_dy_mm": 4.0},
        sigma={"damping.gamma_per_s": 0.01, "clamp.rotation_centre_dy_mm": 0.03},
        rms=1e-4,
    )
    plot_fit_overlay(result, objective, shapes, fit, tmp_path / "overlay.png")
    fig = figures["overlay.png"]
    strip, x_panel, y_panel, colourbar = fig.axes
    assert strip.get_xlabel() == "x from the clamp edge (mm)"
    assert [line for line in strip.get_lines() if line.get_marker() == "o"]  # markers over the strip
    for panel, column, axis in ((x_panel, 0, "x"), (y_panel, 1, "y")):
        assert panel.get_ylabel() == f"residual {axis} (mm)"
        drawn = panel.collections[0].get_offsets()
        np.testing.assert_allclose(drawn[:, 0], shapes.t)
        np.testing.assert_allclose(drawn[:, 1], residual.reshape(-1, 2)[:, column] * 1e3)
    assert y_panel.get_xlabel() == "measured time (s)"
    assert colourbar.get_ylabel() == "marker's arc length s (mm)"
    assert "RMS 0.1 mm" in fig._suptitle.get_text() and "±" in fig._suptitle.get_text()
    on_the_page(fig)


def test_the_tracked_overlay_keys_time_and_reads_at_page_size():
    import matplotlib.pyplot as plt

    from warpcloth.track.markers import Tracked
    from warpcloth.track.overlay import FONT_SIZE, overlay_figure

    n_frames, n_markers = 5, 4
    t = np.linspace(0.0, 0.2, n_frames)
    s = np.arange(1, n_markers + 1) * 20.0
    mm = np.stack([np.column_stack([np.sin(f) * s / 10, -s]) for f in range(n_frames)])
    px = mm * 3 + 100
    tracked = Tracked(
        np.arange(n_frames), t, s, px, mm, np.full(mm.shape[:2], 0.01), np.full(mm.shape[:2], 0.003), np.ones(n_frames)
    )
    fig = overlay_figure(np.full((400, 400), 128, np.uint8), tracked, 2)
    fig.canvas.draw()
    image, shapes, colourbar = fig.axes
    assert colourbar.get_ylabel() == "t (s)"  # the key to the shapes' colours
    assert colourbar.get_ylim() == pytest.approx((0.0, 0.2))
    assert len(shapes.get_lines()) == n_frames + 1  # every frame, and the clamp's point
    assert [line.get_label() for line in shapes.get_lines()][-2:] == ["frame 2 (left)", "clamp's lowest point at rest"]
    texts = [shapes.xaxis.label, shapes.yaxis.label, shapes.title, image.title, *image.texts]
    assert min(text.get_fontsize() for text in texts) >= FONT_SIZE >= 10
    assert [a.get_text() for a in image.texts] == [f"{v:g}" for v in s]
    on_the_page(fig)
    plt.close(fig)


@pytest.mark.slow
def test_the_clamp_fit_prints_what_it_determines_and_marks_what_it_does_not(tmp_path):
    t, theta = read_encoder("impulsive_rotation_encoder", None)
    values = {v.name.split(" ")[0]: v for v in parameter_uncertainties(fit_clamp_motion(t, theta), t, theta)}
    # the record's truth: at rest until 0, 3.2e4 t⁴ to 0.05 s, 16 rad/s to 0.12 s, reading 0.25°
    for name in ("onset", "break", "a1", "a2", "a3", "a4"):
        assert not values[name].determined and "not determined" in values[name].text(), values[name]
    for name, truth in (("θ0", np.radians(0.25)), ("stop", 0.12), ("ω1", 16.0)):
        value = values[name]
        assert value.determined and abs(value.value - truth) < 3 * value.sigma, value
    encoder = ("impulsive_rotation_encoder", "--scene", "impulsive_rotation")
    done = run_cli("clamp", "fit-angle", *encoder, "-o", "r.toml", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "determined: θ(t) itself, within the noise" in done.stdout
    printed = [line.strip() for line in done.stdout.splitlines() if line.startswith("  ")]
    assert len(printed) == len(values)
    for line in printed:  # every value with its σ, or marked
        assert re.search(r" = \S+ ± \S+", line) or ": not determined (" in line, line
    assert "onset = 0.008 s: not determined" in done.stdout


def test_the_tensile_coefficients_are_marked_where_only_the_curve_is_determined():
    from warpcloth.calibrate import kes

    loop = kes.read_tensile_csv("kes_fb1_example")
    fit = kes.fit_tensile(loop)
    values = fit.values()
    assert [v.name for v in values] == ["a1", "a2", "a3", "a4"]
    # a quartic over 6 % of strain: the coefficients trade (a4 3.29e7 against the 2.93e7 that
    # made the loop), the curve is within its RMS
    assert not any(v.determined for v in values) and all("multiple correlation" in v.why for v in values)
    assert np.all(np.isfinite([v.sigma for v in values]))


def test_the_fit_progress_bar_ends_full_and_shows_the_rms_in_mm(monkeypatch):
    from warpcloth.calibrate.motion_fit import search

    stream = io.StringIO()
    monkeypatch.setattr(search, "tqdm", lambda **kw: search_tqdm(file=stream, **kw))
    objective = SimpleNamespace(launches=0, values=lambda u: {})
    history = search._History(objective, 26, True)
    for rms in (2e-3, 5e-4, 2.1e-4):
        history("step", np.zeros(1), 0.0, rms)
    history.close()
    last = stream.getvalue().replace("\r", "\n").strip().splitlines()[-1]
    assert "100%" in last and "3/3" in last and "rms=0.21 mm" in last, last


def search_tqdm(**kw):
    from tqdm import tqdm

    return tqdm(**kw)
