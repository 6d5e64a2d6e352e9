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
from warpcloth.errors import DataFileError
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


def test_render_draws_the_sheet_where_it_is(shear_swing, tmp_path):
    out, result = shear_swing
    last = len(result.frame_times) - 1
    done = run_cli("render", out, "--out", tmp_path / "r", "--times", "0", str(result.frame_times[last]))
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (tmp_path / "r").iterdir())
    assert names == ["frame_00000.png", f"frame_{last:05d}.png", "motion.gif"]

    def sheet_columns(path):
        image = pixels(path)
        cloth = (image[..., 0] - image[..., 2] > 15) & (image.max(axis=2) < 250)  # brown, not white or grey
        return np.nonzero(cloth)[1].mean(), cloth.sum()

    # the clamp carries the sheet 20 mm along +z, which the camera (in front, +x) sees as leftward
    shift = result.markers[-1, 0, :, 2] - result.markers[0, 0, :, 2]  # the last sample is the last frame
    assert shift.min() > 0.019
    start, start_count = sheet_columns(tmp_path / "r" / "frame_00000.png")
    end, end_count = sheet_columns(tmp_path / "r" / f"frame_{last:05d}.png")
    assert start_count > 10_000 and end_count > 10_000
    assert end < start - 40
    gif = Image.open(tmp_path / "r" / "motion.gif")
    assert gif.n_frames == len(range(0, last + 1, 3))  # 60 frames/s: every third frame plays in real time
    one_line_refusal(run_cli("render", out, "--out", tmp_path / "r2", "--times", "9"), "--times", "9 s is outside")


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
