"""Looking at a sheet run (stage 3, issue 23): `warpcloth plot`, `export-usd` and `render` on
a sheet run directory read it back as the run recorded it, write the sheet's figures, its
mesh and its frames, and refuse a strip's option in one line naming it."""

import json
import re
import shutil

import numpy as np
import pytest
from conftest import overrides, run_cli
from PIL import Image
from pxr import Usd, UsdGeom

from warpcloth import bodies
from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.io.sheet_run_dir import read_sheet_run
from warpcloth.runs import simulate
from warpcloth.scene.sheet_build import load_sheet_scene

COARSE = overrides(
    run__duration_s=0.1, release__settle_time_s=0.05, sheet__spacing_warp_mm=10.0, sheet__spacing_weft_mm=10.0
)


@pytest.fixture(scope="module")
def shear_swing(tmp_path_factory):
    """The bundled shear swing, short and coarse: its run directory and the in-memory result."""
    out = tmp_path_factory.mktemp("sheet") / "shear_swing"
    result = simulate(load_sheet_scene("shear_swing", COARSE), out=out)
    return out, result


def pixels(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


def one_line_refusal(proc, *words):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for word in words:
        assert word in lines[0], lines[0]


def test_the_run_directory_reads_back_as_the_run_recorded_it(shear_swing):
    out, result = shear_swing
    # the registry reads the body off meta.json; a directory without one is left to the strip's reader
    assert bodies.of_run(out).name == "sheet" and bodies.of_run(out / "no_such_run").name == "strip"
    samples = read_sheet_run(out).samples()
    # probes and markers are stored as "%.17g", which round-trips a float64 exactly
    np.testing.assert_array_equal(samples.probes, result.probes)
    np.testing.assert_array_equal(samples.markers, result.markers)
    np.testing.assert_allclose(samples.t, result.t, rtol=0, atol=1e-9)  # t as "%.10g"
    np.testing.assert_array_equal(samples.frames, result.frames)
    np.testing.assert_array_equal(samples.energy_total(), result.energy_total())
    # the budget derived from the probes' descriptions is the sum written out by hand
    p = result.probe
    by_hand = (
        p("kinetic")
        + p("gravitational")
        + p("tensile")
        + p("elastic_work")
        + p("hysteresis_work")
        + p("damping_work")
        - p("drive_work")
    )
    assert np.array_equal(by_hand, result.energy_total())


def test_plot_writes_the_sheet_figures(shear_swing, tmp_path):
    out, _ = shear_swing
    done = run_cli("plot", out, "--out", tmp_path / "fig", "--dpi", "60")
    assert done.returncode == 0, done.stderr
    paths = sorted((tmp_path / "fig").iterdir())
    assert [p.name for p in paths] == ["sheet_run.png", "sheet_shapes.png"]
    for path in paths:
        image = pixels(path)
        assert image.shape[1] >= 600 and image.std() > 5  # 10 in × 60 dpi, more than a flat background
    # an existing figure directory is not replaced without --overwrite
    one_line_refusal(run_cli("plot", out, "--out", tmp_path / "fig"), "--out", "--overwrite")
    done = run_cli("plot", out, "--out", tmp_path / "fig", "--overwrite", "--format", "svg")
    assert done.returncode == 0, done.stderr
    assert {"sheet_run.svg", "sheet_shapes.svg"} <= {p.name for p in (tmp_path / "fig").iterdir()}


@pytest.mark.parametrize(
    "command, option, value",
    [
        ("plot", "--measured", "laser.csv"),
        ("plot", "--times", "0.05"),
        ("plot", "--metric", "first_period_s"),
        ("plot", "--variants", "0"),
        ("export-usd", "--ribbon", None),
        ("export-usd", "--frames-per-clip", "2"),
        ("render", "--where", "damping.gamma_per_s<1"),
    ],
)
def test_a_strip_option_on_a_sheet_run_is_one_line_naming_it(shear_swing, tmp_path, command, option, value):
    out, _ = shear_swing
    target = ("-o", tmp_path / "stage.usda") if command == "export-usd" else ("--out", tmp_path / "result")
    given = (option,) if value is None else (option, value)
    one_line_refusal(run_cli(command, out, *target, *given), f"error in option: {option}", "is a sheet run")
    assert not any(tmp_path.iterdir())  # refused before anything is written


def test_export_usd_writes_the_mesh_the_run_recorded(shear_swing, tmp_path):
    out, result = shear_swing
    run = read_sheet_run(out)
    done = run_cli("export-usd", out, "-o", tmp_path / "sheet.usda")
    assert done.returncode == 0, done.stderr
    stage = Usd.Stage.Open(str(tmp_path / "sheet.usda"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Sheets/sheet_0000"))
    # a 100 × 110 mm rectangle (10 mm held) at 10 mm: 11 × 12 nodes, 10 × 11 quads
    counts = mesh.GetFaceVertexCountsAttr().Get()
    assert len(counts) == 10 * 11 == len(run.faces) and set(counts) == {4}
    assert np.array_equal(np.array(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 4), run.faces)
    points = mesh.GetPointsAttr()
    assert points.GetTimeSamples() == list(range(len(result.frame_times)))
    for f in (0, len(result.frame_times) - 1):
        shape = np.array(points.Get(f))
        assert shape.shape == (11 * 12, 3)
        np.testing.assert_allclose(shape, result.frames[f, 0], rtol=0, atol=1e-7)  # float32 on the stage
    one_line_refusal(run_cli("export-usd", out, "-o", tmp_path / "sheet.usda"), "-o", "--overwrite")


def sheet_pixels(image):
    """The sheet's pixels: light (its quads, grey to coloured by their shear), left of the colour bar."""
    mask = (image.max(axis=2) < 245) & (image.min(axis=2) > 120)
    mask[:, int(0.8 * image.shape[1]) :] = False
    return mask


def clamp_pixels(image):
    """The clamp's pixels: dark and a little blue (CLAMP_COLOUR shaded), unlike the black text and grey edges."""
    return (image.max(axis=2) < 110) & (image[..., 2] - image[..., 0] >= 3)


def test_render_draws_the_sheet_and_its_clamp_where_they_are(shear_swing, tmp_path):
    out, result = shear_swing
    last = len(result.frame_times) - 1
    done = run_cli("render", out, "--out", tmp_path / "r", "--times", "0", str(result.frame_times[last]))
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (tmp_path / "r").iterdir())
    assert names == ["frame_00000.png", f"frame_{last:05d}.png", "motion.gif"]

    def where(path):
        image = pixels(path)
        sheet, clamp = sheet_pixels(image), clamp_pixels(image)
        rows, columns = np.nonzero(sheet)
        clamp_rows, clamp_columns = np.nonzero(clamp)
        return columns.mean(), sheet.sum(), np.median(rows), clamp_columns.mean(), clamp.sum(), clamp_rows.mean()

    # the clamp carries the sheet 20 mm along +z, which the camera (in front, +x) sees as leftward
    shift = result.markers[-1, 0, :, 2] - result.markers[0, 0, :, 2]  # the last sample is the last frame
    assert shift.min() > 0.019
    start, start_count, start_row, clamp_start, clamp_count, clamp_row = where(tmp_path / "r" / "frame_00000.png")
    end, end_count, _, clamp_end, _, _ = where(tmp_path / "r" / f"frame_{last:05d}.png")
    assert start_count > 10_000 and end_count > 10_000
    assert end < start - 40
    # the clamp is a solid bar above the sheet, and moves with it
    assert clamp_count > 3_000 and clamp_row < start_row - 100
    assert clamp_end < clamp_start - 40 and abs((clamp_start - clamp_end) - (start - end)) < 15
    gif = Image.open(tmp_path / "r" / "motion.gif")
    assert gif.n_frames == len(range(0, last + 1, 3))  # 60 frames/s: every third frame plays in real time
    one_line_refusal(run_cli("render", out, "--out", tmp_path / "r2", "--times", "9"), "--times", "9 s is outside")


def test_render_colours_each_quad_by_its_shear(tmp_path):
    from warpcloth.viz.render import render_sheet_run

    # the twist shears the sheet's two halves opposite ways: both ends of the diverging map show
    scene = load_sheet_scene("twist", [*COARSE, "run.duration_s=0.3"])
    simulate(scene, out=tmp_path / "twist")
    run = read_sheet_run(tmp_path / "twist")
    paths = render_sheet_run(run, tmp_path / "r", times=np.array([0.0, 0.3]), movie=None)
    for path, sheared in zip(paths, (False, True), strict=True):
        image = pixels(path)
        sheet = sheet_pixels(image)
        red = sheet & (image[..., 0] - image[..., 2] > 50)
        blue = sheet & (image[..., 2] - image[..., 0] > 50)
        assert (min(red.sum(), blue.sum()) > 5_000) == sheared, (path, red.sum(), blue.sum())
        # the colour bar, right of the sheet, spans both ends whatever the frame
        bar = image[:, int(0.8 * image.shape[1]) :]
        assert ((bar[..., 0] - bar[..., 2] > 100).sum() > 100) and ((bar[..., 2] - bar[..., 0] > 100).sum() > 100)
        assert clamp_pixels(image).sum() > 3_000


def test_the_shear_angle_of_a_quad_is_the_kernels():
    from test_sheet import cell_shear_angle

    from warpcloth.sheet.geometry import quad_shear_angles

    # a rhombus whose warp side (down, −y) leans toward its weft side (+z) by 3° shears by +3°,
    # wherever it lies
    phi = np.radians(3.0)
    x00, x10, x01 = np.zeros(3), np.array([0.0, -np.cos(phi), np.sin(phi)]) * 5e-3, np.array([0.0, 0.0, 1.0]) * 5e-3
    rng = np.random.default_rng(1)
    turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    corners = np.array([x00, x10, x10 + x01, x01]) @ turn.T + rng.normal(size=3)
    quads = np.array([[0, 1, 2, 3]])
    assert quad_shear_angles(corners, quads)[0] == pytest.approx(cell_shear_angle(*corners[[0, 1, 3, 2]]), abs=1e-15)
    frames = rng.normal(size=(2, 4, 3))  # any quad, any frame: the tests' reference to round-off
    expected = [cell_shear_angle(*f[[0, 1, 3, 2]]) for f in frames]
    np.testing.assert_allclose(quad_shear_angles(frames, quads)[:, 0], expected, rtol=0, atol=1e-14)
    assert quad_shear_angles(corners, quads)[0] == pytest.approx(phi, abs=1e-12)


def test_the_colour_limit_is_a_round_number_at_or_above_the_peak():
    from warpcloth.viz.render import colour_limit

    assert [colour_limit(p) for p in (0.037, 0.12, 1.12, 3.0, 7.0, 9.5)] == pytest.approx(
        [0.04, 0.15, 1.5, 3.0, 8.0, 10.0]
    )
    assert colour_limit(0.0) == 1e-6  # a sheet that never shears: a range VTK can draw


def _rewrite_csv(file, change):
    lines = file.read_text().splitlines()
    change(lines)
    file.write_text("\n".join(lines) + "\n")


def _swap(lines, a, b):
    lines[a], lines[b] = lines[b], lines[a]


def _set_cell(lines, line, column, value):
    cells = lines[line].split(",")
    cells[column] = value
    lines[line] = ",".join(cells)


def _meta(out, change):
    meta = json.loads((out / "meta.json").read_text())
    change(meta)
    (out / "meta.json").write_text(json.dumps(meta))


def _geometry(out, name, change):
    with np.load(out / "geometry.npz") as archive:
        arrays = dict(archive)
    change(arrays[name])
    np.savez(out / "geometry.npz", **arrays)


DAMAGE = {
    # issue 39: each was read as valid, or ended in a traceback or a segmentation fault
    "a face past the nodes": (
        lambda out: _geometry(out, "faces", lambda a: a.__setitem__((3, 1), 10**6)),
        "geometry.npz: faces is not the geometry this warpcloth cuts from the run's scene",
    ),
    "a shifted lattice": (
        lambda out: _geometry(out, "lattice", lambda a: a.__setitem__((0, 0), 7)),
        "geometry.npz: lattice is not the geometry this warpcloth cuts from the run's scene",
    ),
    "a marker dropped from meta.json": (
        lambda out: _meta(out, lambda m: m["markers"].pop()),
        "meta.json: markers name nodes",
    ),
    "a marker moved to another node": (
        lambda out: _meta(out, lambda m: m["markers"][0].__setitem__("node", 5)),
        "meta.json: markers name nodes [5,",
    ),
    "a marker index past the markers": (
        lambda out: _rewrite_csv(out / "markers.csv", lambda ls: _set_cell(ls, 6, 2, "9")),
        "markers.csv, line 7: marker is 9, but this row is marker 1 of sheet 0",
    ),
    "marker rows out of time order": (
        lambda out: _rewrite_csv(out / "markers.csv", lambda ls: _swap(ls, 2, 10)),
        "markers.csv, line 3: t is",
    ),
    "probe rows out of time order": (
        lambda out: _rewrite_csv(out / "probes.csv", lambda ls: _swap(ls, 3, 4)),
        "probes.csv, line 5: t = 0.003333333333 s of sheet 0 comes after t = 0.005 s (line 4)",
    ),
    "a probe row of a sheet the run lacks": (
        lambda out: _rewrite_csv(out / "probes.csv", lambda ls: _set_cell(ls, 5, 1, "3")),
        "probes.csv, line 6: sheet is 3, but the run has 1",
    ),
    "frame times that go back": (
        lambda out: np.save(out / "frame_times.npy", np.load(out / "frame_times.npy")[::-1].copy()),
        "frame_times.npy: frame 1 at t = ",
    ),
    "the run's scene copy changed": (
        lambda out: (out / "scene.toml").write_text(
            (out / "scene.toml").read_text().replace("free_length_mm = ", 'free_length_mm = "x" # ', 1)
        ),
        "scene.toml: is the run's copy of its scene and this warpcloth refuses it (sheet.free_length_mm",
    ),
    "two sheets claimed": (
        lambda out: _meta(out, lambda m: m.__setitem__("n_sheets", 2)),
        "meta.json: n_sheets is 2, but the run directory holds one scene.toml",
    ),
}


@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_a_damaged_sheet_run_is_refused_by_every_reader_naming_the_file(shear_swing, tmp_path, damage):
    original, _ = shear_swing
    out = tmp_path / "damaged"
    shutil.copytree(original, out)
    change, message = DAMAGE[damage]
    change(out)
    with pytest.raises(DataFileError, match=re.escape(message)):
        read_sheet_run(out)
    for command in (("plot", out, "--out", tmp_path / "fig"), ("export-usd", out, "-o", tmp_path / "s.usda")):
        one_line_refusal(run_cli(*command), message)
    assert not (tmp_path / "fig").exists() and not (tmp_path / "s.usda").exists()


def test_analyse_refuses_a_sheet_run_in_one_line(shear_swing):
    out, _ = shear_swing
    one_line_refusal(run_cli("analyse", out), "is a sheet run: analyse measures a strip's swing", "`plot` draws")


# The figures themselves (issue 40): what each panel draws, in the units a lab reads


def _figure_of(shear_swing):
    from warpcloth.viz.figures.sheet import SheetSetting

    out, _ = shear_swing
    run = read_sheet_run(out)
    return run, SheetSetting.of_scene(run.scene, "shear_swing", run.rest_positions)


def test_the_run_figure_shows_the_markers_against_the_clamp_and_says_what_it_is(shear_swing):
    from warpcloth.viz.figures.sheet import sheet_run_figure

    run, setting = _figure_of(shear_swing)
    samples = run.samples()
    fig = sheet_run_figure(samples, setting)
    markers, shear, bending, budget = fig.axes[:4]
    assert fig._suptitle.get_text() == "shear_swing (wool90-nylon10): markers, shear, bending and energy"
    # the clamp carries the markers 20 mm along z; against it they move a few tenths of a mm
    drawn = np.concatenate([line.get_ydata() for line in markers.get_lines()])
    assert np.ptp(samples.markers[:, 0, :, 2]) * 1e3 > 19 and 0.01 < np.abs(drawn).max() < 1.0
    assert markers.get_ylabel() == "displacement against the clamp (mm)"
    # a compact legend: one entry per marker and one per coordinate drawn, not 12
    legends = [markers.get_legend(), *(a for a in markers.artists if isinstance(a, plt_legend()))]
    entries = sum(len(leg.get_texts()) for leg in legends)
    assert entries <= 4 + 3, entries
    assert "(-100, -50)" in {t.get_text() for leg in legends for t in leg.get_texts()}
    assert shear.get_xlabel() == "shear angle φ (°)" and "probed cell at (y, z)" in shear.get_title()
    assert len(shear.get_lines()[0].get_xdata()) == len(samples.t)
    assert bending.get_xlabel() == "curvature K (1/cm)" and "probed warp hinge" in bending.get_title()
    assert budget.get_lines() and budget.get_xlabel() == "t (s)"


def plt_legend():
    import matplotlib.legend

    return matplotlib.legend.Legend


def test_a_probe_at_round_off_is_said_not_drawn(tmp_path):
    from warpcloth.viz.figures.sheet import SheetSetting, sheet_run_figure

    # a sheet driven in its plane with no waviness stays in it to round-off: its hinge never bends
    out = tmp_path / "flat"
    simulate(load_sheet_scene("shear_swing", [*COARSE, "sheet.initial_waviness_mm=0"]), out=out)
    run = read_sheet_run(out)
    fig = sheet_run_figure(run.samples(), SheetSetting.of_scene(run.scene, "flat", run.rest_positions))
    bending = fig.axes[2]
    assert not bending.get_lines()
    said = " ".join(t.get_text() for t in bending.texts)
    assert "stays at round-off" in said and "output.probe_hinge_mm" in said
    assert fig.axes[1].get_lines()  # the cell at the clamp's corner still shears


def test_the_shapes_figure_draws_a_panel_per_time_with_lines_of_the_mesh(shear_swing):
    from warpcloth.viz.figures.sheet import sheet_shapes_figure

    run, setting = _figure_of(shear_swing)
    fig = sheet_shapes_figure(run.samples(), setting, count=3)
    panels = [ax for ax in fig.axes if ax.get_title().startswith("t = ")]
    assert len(panels) == 2 * 3  # from the side and from below, at each of three times
    assert {ax.get_title() for ax in panels} == {f"t = {t:.3f} s" for t in run.frame_times[[0, 3, 6]]}
    # 11 columns of nodes seen from the side, 12 rows (the clamped row included) from below
    assert sorted({len(ax.get_lines()) for ax in panels}) == [11, 12]
    assert "x out of the plane (mm)" in {ax.get_xlabel() for ax in panels}
    assert "the sheet's shape seen from the clamp" in fig._suptitle.get_text()
    with pytest.raises(ArgumentError, match="count"):
        sheet_shapes_figure(run.samples(), setting, count=0)


def test_the_sheet_sweep_plot_names_its_axes_and_does_not_join_three_points(tmp_path):
    import pandas as pd

    from warpcloth.viz.figures.sweeps import sweep_figure

    g, gamma = "shear.rigidity_gf_per_cm_deg", "damping.gamma_per_s"
    summary = pd.DataFrame({g: [0.5, 1.0, 2.0] * 2, gamma: [0.1] * 3 + [1.0] * 3, "peak_shear_angle_deg": range(6)})
    ax = sweep_figure(summary, "peak_shear_angle_deg", g).axes[0]
    assert ax.get_xlabel() == "G (gf/(cm·°))" and ax.get_ylabel() == "probed cell's peak shear angle (°)"
    assert {t.get_text() for t in ax.get_legend().get_texts()} == {"γ = 0.1 s⁻¹", "γ = 1 s⁻¹"}
    assert all(line.get_linestyle() == "None" for line in ax.get_lines())  # points, not a line
    assert "points, not joined" in " ".join(t.get_text() for t in ax.texts)
    dense = pd.DataFrame({g: np.linspace(0.25, 4, 9), "marker_0_peak_z_against_clamp_mm": np.ones(9)})
    ax = sweep_figure(dense, "marker_0_peak_z_against_clamp_mm", g).axes[0]
    assert ax.get_lines()[0].get_linestyle() == "-"
    assert ax.get_ylabel() == "marker 0's peak sideways z against the clamp (mm)"


def test_the_sheet_fit_overlay_draws_the_markers_against_the_clamp_and_the_residuals(tmp_path):
    from types import SimpleNamespace

    from warpcloth.calibrate.motion_fit.sheet import SheetObjective, sheet_free_parameters
    from warpcloth.io.measured import read_sheet_markers
    from warpcloth.scene import read_scene_file
    from warpcloth.scene.overrides import apply_overrides
    from warpcloth.viz.figures import fits

    coarse = ["sheet.spacing_warp_mm=10", "sheet.spacing_weft_mm=10", "run.duration_s=0.3"]
    measured = read_sheet_markers("shear_swing_markers")
    base = apply_overrides(read_scene_file("shear_swing"), coarse)
    objective = SheetObjective(base, measured, sheet_free_parameters("G", load_sheet_scene("shear_swing", coarse)))
    result = objective.run(np.array([[0.5]]))
    g = "shear.rigidity_gf_per_cm_deg"
    fit = SimpleNamespace(parameters={g: 1.1}, sigma={g: 0.02}, rms=4e-5, shift_s=0.0)
    drawn = {}
    saved = fits.common.save
    fits.common.save = lambda fig, path: drawn.setdefault("fig", fig) and saved(fig, path)
    try:
        path = fits.plot_fit_overlay(result, objective, measured, fit, tmp_path / "overlay.png")
    finally:
        fits.common.save = saved
    assert pixels(path).std() > 5
    fig = drawn["fig"]
    assert "G = 1.1 ± 0.02 gf/(cm·°)" in fig._suptitle.get_text() and "wool90-nylon10" in fig._suptitle.get_text()
    (y_track, y_residual), (z_track, z_residual) = np.array(fig.axes).reshape(2, 2)
    assert z_track.get_ylabel() == "z against the clamp (mm)"
    assert z_residual.get_ylabel() == "simulated − measured z (mm)"
    # against the clamp the measured swing is a few tenths of a mm, not its 20 mm travel
    measured_z = np.concatenate([line.get_ydata() for line in z_track.get_lines() if line.get_linestyle() == "None"])
    assert 0.05 < np.abs(measured_z).max() < 1.0
    residual = np.concatenate([line.get_ydata() for line in z_residual.get_lines() if line.get_linestyle() == "None"])
    assert len(residual) == (measured.marker >= 0).sum() and np.abs(residual).max() < 0.5


@pytest.mark.parametrize("angle", [30.0, 45.0])
def test_the_shapes_figure_has_lines_at_any_cut(angle):
    # a cut at 30° has no two nodes at one y or z: its lines are bands a spacing wide (it
    # drew empty panels); on the bias the rows group exactly, as before
    import math

    from warpcloth.sheet import bias_strip
    from warpcloth.viz.figures.sheet import _lines

    rest = bias_strip(0.1, 0.03, 0.01, 0.005, angle=math.radians(angle)).rest_positions
    for along, across in ((1, 2), (2, 1)):
        lines = _lines(rest, along, across)
        drawn = np.concatenate(lines)
        assert len(np.unique(drawn)) == len(drawn) > 0.9 * len(rest)  # each node on one line, nearly all drawn
        assert all((np.diff(rest[line, along]) >= 0).all() for line in lines)
        if angle == 45.0:  # a row or a column of nodes at one rest coordinate
            assert all(np.ptp(rest[line, across]) < 1e-9 for line in lines)
        else:  # a band a spacing wide
            assert max(np.ptp(rest[line, across]) for line in lines) <= 0.005 + 1e-12
