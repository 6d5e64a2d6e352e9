"""Sheet scenes from the command line (stage 3, issue 23): the bundled scenes run into sheet
run directories whose files agree with each other, the USD export reads back as the mesh
it was written from, and bad input is one line naming the field and where it was set."""

import importlib.resources
import json

import numpy as np
import pytest
from conftest import run_cli
from pxr import Usd, UsdGeom

import warpcloth as wc
from warpcloth.io.sheet_run_dir import read_sheet_run
from warpcloth.scene.sheet import SheetScene, read_sheet_scene
from warpcloth.scene.sheet_build import load_sheet_scene

SHEETS = ("shear_swing", "twist", "bias_strip")
SHORT = ("--set", "run.duration_s=0.1", "--set", "release.settle_time_s=0.05", "--no-progress")
COARSE = {  # 10 mm cells for the square sheets; the bias strip is small at its own 5 mm
    "shear_swing": ("--set", "sheet.spacing_warp_mm=10", "--set", "sheet.spacing_weft_mm=10"),
    "twist": ("--set", "sheet.spacing_warp_mm=10", "--set", "sheet.spacing_weft_mm=10"),
    "bias_strip": (),
}


def bundled_text(name):
    return (importlib.resources.files("warpcloth.scenes") / f"{name}.toml").read_text()


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each bundled sheet scene, short and coarse, run by the CLI (and exported to USD)."""
    root = tmp_path_factory.mktemp("sheet_runs")
    done = {}
    for name in SHEETS:
        proc = run_cli("run", name, "--out", root / name, "--usd", root / f"{name}.usda", *SHORT, *COARSE[name])
        assert proc.returncode == 0, proc.stderr
        done[name] = (root / name, root / f"{name}.usda", proc.stdout)
    return done


@pytest.mark.parametrize("name", SHEETS)
def test_a_sheet_run_directory_agrees_with_itself(runs, name):
    out, _, stdout = runs[name]
    run = read_sheet_run(out)
    assert run.complete and run.meta["kind"] == "sheet"
    assert len(run.rest_positions) == run.meta["n_nodes"] == run.frames.shape[2]
    # frames and markers are recorded from one state: equal, bit for bit, at every frame
    markers = run.meta["markers"]
    assert markers, "every bundled sheet scene tracks markers"
    for frame, t in enumerate(run.frame_times):
        # t is stored to 10 digits; samples lie 1.7 ms apart
        rows = run.markers[np.isclose(run.markers["t"], t, rtol=0, atol=1e-9)].sort_values("marker")
        assert len(rows) == len(markers)
        nodes = [m["node"] for m in markers]
        np.testing.assert_array_equal(rows[["x", "y", "z"]].to_numpy(), run.frames[frame, 0, nodes])
    # the energy budget (docs/model.md §17) holds to a small part of the work the clamp did
    p = run.probes
    budget = (
        p.kinetic + p.gravitational + p.tensile + p.elastic_work + p.hysteresis_work + p.damping_work - p.drive_work
    ).to_numpy()
    drive = np.abs(p.drive_work.to_numpy()).max()
    assert drive > 0
    assert np.abs(budget - budget[0]).max() < 1e-3 * drive
    # the recorded scene re-reads to itself, with the step auto chose
    scene = read_sheet_scene(out / "scene.toml")
    assert scene.to_dict() == run.scene.to_dict()
    assert scene.integrator.dt_chosen_by == "auto" and scene.integrator.dt_s > 0
    assert "energy budget: largest drift" in stdout and "peak shear angle" in stdout
    meta = json.loads((out / "meta.json").read_text())
    assert meta["committed"]["frames"] == len(run.frame_times)


@pytest.mark.parametrize("name", SHEETS)
def test_the_usd_mesh_reads_back(runs, name):
    out, usd, _ = runs[name]
    run = read_sheet_run(out)
    stage = Usd.Stage.Open(str(usd))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == run.scene.output.frame_rate_hz
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Sheets/sheet_0000"))
    points = mesh.GetPointsAttr()
    assert points.GetTimeSamples() == list(range(len(run.frame_times)))
    assert len(points.Get(0)) == run.meta["n_nodes"]
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [4] * len(run.faces) == [4] * run.meta["n_faces"]
    last = len(run.frame_times) - 1
    np.testing.assert_allclose(np.array(points.Get(last)), run.frames[last, 0], atol=1e-6)  # float32 in USD
    lattice = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("warpcloth:lattice").Get()
    np.testing.assert_array_equal(np.array(lattice), run.lattice)
    warp = np.array(UsdGeom.PrimvarsAPI(mesh).GetPrimvar("warpcloth:warp_direction").Get())
    assert warp.shape == (len(run.faces), 3)
    expected = (0.0, -1.0, 0.0) if run.scene.sheet.cut == "rectangle" else (0.0, -np.sqrt(0.5), np.sqrt(0.5))
    # in the sheet's plane, as cut; out of it by the hung sheet's waviness slope (A π / L at most)
    in_plane = warp[:, 1:] / np.linalg.norm(warp[:, 1:], axis=1, keepdims=True)
    np.testing.assert_allclose(in_plane, np.broadcast_to(expected[1:], in_plane.shape), atol=1e-6)
    slope = np.pi * run.scene.sheet.initial_waviness_mm / run.scene.sheet.free_length_mm
    assert np.abs(warp[:, 0]).max() <= slope + 1e-6


def test_faces_cover_the_cut(runs):
    # a 100 × 110 mm rectangle (10 mm held) at 10 mm: 10 × 11 quads, the clamped ones included
    run = read_sheet_run(runs["shear_swing"][0])
    assert len(run.faces) == 10 * 11


def one_line_refusal(proc, *words):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def line_of(text, start):
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start))


def test_a_wrong_sheet_field_names_the_field_file_and_line(tmp_path):
    text = bundled_text("shear_swing")
    scene = tmp_path / "sheet.toml"
    scene.write_text(text.replace("spacing_warp_mm = 5.0", "spacing_warp_mm = -5.0"))
    one_line_refusal(
        run_cli("run", scene, "--out", tmp_path / "r"),
        "sheet.spacing_warp_mm",
        f"{scene}, line {line_of(text, 'spacing_warp_mm')}",
    )
    scene.write_text(text.replace('cut = "rectangle"', 'cut = "circle"'))
    one_line_refusal(
        run_cli("run", scene, "--out", tmp_path / "r"), "sheet.cut", "rectangle, bias", f"line {line_of(text, 'cut')}"
    )
    scene.write_text(text.replace("spacing_weft_mm = 5.0", "spacing_weft_mm = 3.0"))
    one_line_refusal(run_cli("run", scene, "--out", tmp_path / "r"), "sheet.spacing_weft_mm", "does not divide")
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    "command, scene, override, words",
    [
        # issue 39: these blamed the scene ("this is a sheet scene") or listed fields as unknown
        ("run", "damped_swing", "sheet.cut=rectangle", ("sheet: bundled scene damped_swing is a strip scene",)),
        ("run", "shear_swing", "strip.spacing_mm=2", ("strip: bundled scene shear_swing is a sheet scene",)),
        ("sweep", "damped_swing_sweep", "sheet.cut=bias", ("bundled scene damped_swing_sweep is a strip scene",)),
        # a length whose node count overflows is named before the cut is built (it was NumPy's ValueError)
        ("run", "shear_swing", "sheet.free_length_mm=1e308", ("sheet.free_length_mm: 1e+308 mm", "inf nodes")),
    ],
)
def test_an_override_of_the_other_body_or_beyond_a_count_is_named(tmp_path, command, scene, override, words):
    done = run_cli(command, scene, "--set", override, "--out", tmp_path / "o")
    one_line_refusal(done, *words, f"(set by the override {override})")
    assert not (tmp_path / "o").exists()


def test_a_scene_is_a_strip_or_a_sheet(tmp_path):
    both = tmp_path / "both.toml"
    both.write_text("[strip]\nspacing_mm = 5.0\n" + bundled_text("twist"))
    one_line_refusal(run_cli("run", both), "both [strip] and [sheet]", str(both))
    neither = tmp_path / "neither.toml"
    neither.write_text(bundled_text("twist").replace("[sheet]", "[geometry]"))
    one_line_refusal(run_cli("run", neither), "neither [strip] nor [sheet]", "clamp.rotation_segments")
    # the public API takes either body the same way (issue 37: it used to refuse a sheet)
    sheet = wc.load_scene("twist", ["run.duration_s=0.01"])
    assert isinstance(sheet, SheetScene)
    assert wc.simulate(sheet).body == "sheet"
    with pytest.raises(wc.SceneError, match="both"):
        wc.scene_from_dict({"strip": {}, "sheet": {}})


def test_a_step_above_the_stability_estimate_is_refused(tmp_path):
    estimate = 4.941e-5  # SheetSolver.stable_step() of the bundled wool at 5 mm (its twist term included)
    line = one_line_refusal(
        run_cli("run", "shear_swing", "--set", "integrator.dt_s=1e-4", "--out", tmp_path / "r"),
        "integrator.dt_s",
        "stability estimate",
        "set by the override integrator.dt_s=1e-4",
    )
    assert f"{estimate:.4g} s" in line
    scene = load_sheet_scene("shear_swing", ["integrator.dt_s=4.9e-5", "run.duration_s=0.01"])
    assert scene.integrator.dt_s == 4.9e-5 and scene.integrator.dt_chosen_by == "scene"


def test_a_marker_off_the_sheet_is_refused(tmp_path):
    one_line_refusal(
        run_cli("run", "twist", "--set", "output.markers_mm=[[-300.0, 0.0]]", "--out", tmp_path / "r"),
        "output.markers_mm[0]",
        "is not on a node of the sheet",
    )
    # between nodes: the run records nodes, so a point between them is refused, naming the nearest
    one_line_refusal(
        run_cli("run", "twist", "--set", "output.markers_mm=[[-52.0, 0.0]]", "--out", tmp_path / "r"),
        "output.markers_mm[0]",
        "the nearest, [-50, 0] mm, is 2 mm away",
    )
    one_line_refusal(
        run_cli("run", "twist", "--set", "output.probe_cell_mm=[-300.0, 0.0]", "--out", tmp_path / "r"),
        "output.probe_cell_mm",
        "from the nearest free cell's centre",
    )
    one_line_refusal(
        run_cli("run", "twist", "--set", "output.probe_hinge_mm=[500.0, 500.0]", "--out", tmp_path / "r"),
        "output.probe_hinge_mm",
        "from the nearest free warp hinge",
    )
    one_line_refusal(
        run_cli("run", "twist", "--set", "output.markers_ij=[[99, 0]]", "--out", tmp_path / "r"),
        "output.markers_ij[0]",
        "not a node of the sheet",
    )


def test_a_clamp_that_would_start_elsewhere_is_refused(tmp_path):
    one_line_refusal(
        run_cli(
            "run",
            "shear_swing",
            "--set",
            "clamp.translation_segments=[{t_start_s = 0.0, t_end_s = 0.05, d_coefficients_mm = [3.0, 0.0, 4000.0]}]",
            "--out",
            tmp_path / "r",
        ),
        "clamp.translation_segments[0].d_coefficients_mm",
        "the clamp cannot teleport",
    )


def test_a_material_without_shear_and_a_weft_density_are_refused(tmp_path):
    wool = (importlib.resources.files("warpcloth.scenes") / "materials" / "wool90-nylon10.toml").read_text()
    material = tmp_path / "plain.toml"
    material.write_text(wool[: wool.index("[shear]")])
    scene = tmp_path / "s.toml"
    scene.write_text(bundled_text("twist").replace('"wool90-nylon10"', f'"{material}"'))
    one_line_refusal(run_cli("run", scene, "--out", tmp_path / "r"), "shear", "needs a shear law")
    material.write_text(wool.replace("[weft]\n", "[weft]\ndensity_g_per_cm2 = 0.01\n"))
    one_line_refusal(run_cli("run", scene, "--out", tmp_path / "r"), "weft.density_g_per_cm2", "one value per fabric")


def test_an_existing_result_is_kept_unless_overwrite(runs, tmp_path):
    out = tmp_path / "keep"
    out.mkdir()
    (out / "thesis.tex").write_text("months of work")
    one_line_refusal(run_cli("run", "bias_strip", "--out", out, *SHORT), "--out", "already holds files")
    assert (out / "thesis.tex").read_text() == "months of work"
    existing = runs["bias_strip"][0]
    before = (existing / "probes.csv").read_bytes()
    one_line_refusal(run_cli("run", "bias_strip", "--out", existing, *SHORT), "--out", "already holds a run")
    assert (existing / "probes.csv").read_bytes() == before
    again = tmp_path / "again"
    assert run_cli("run", "bias_strip", "--out", again, *SHORT).returncode == 0
    done = run_cli("run", "bias_strip", "--out", again, *SHORT, "--set", "damping.gamma_per_s=1.0", "--overwrite")
    assert done.returncode == 0, done.stderr
    assert read_sheet_run(again).scene.damping.gamma_per_s == 1.0


def test_an_interrupted_sheet_run_reads_as_incomplete(tmp_path, monkeypatch):
    from warpcloth.io.sheet_run_dir import SheetRunWriter

    original = SheetRunWriter.write_frames

    def interrupt_after_the_first(self, first, frames):
        original(self, first, frames)
        raise KeyboardInterrupt

    monkeypatch.setattr(SheetRunWriter, "write_frames", interrupt_after_the_first)
    out = tmp_path / "cut"
    proc = run_cli("run", "bias_strip", "--out", out, *SHORT)
    assert proc.returncode == 130 and "marked incomplete" in proc.stderr
    run = read_sheet_run(out)
    assert not run.complete and len(run.frame_times) >= 1 and run.meta["committed"]["frames"] == len(run.frames)
    assert np.isfinite(run.frames).all()


def test_a_diverged_sheet_is_one_message_and_keeps_its_record(tmp_path):
    # a 100 mm jerk in 50 ms shears the corner cell past a 10° limit at t ≈ 0.05 s
    out = tmp_path / "div"
    proc = run_cli(
        "run",
        "shear_swing",
        "--out",
        out,
        *SHORT,
        *COARSE["shear_swing"],
        "--set",
        "clamp.translation_segments=[{t_start_s = 0.0, t_end_s = 0.05, d_coefficients_mm = [0.0, 0.0, 40000.0]}]",
        "--set",
        "integrator.divergence_shear_deg=10",
    )
    assert proc.returncode == 3 and "Traceback" not in proc.stderr
    assert "sheet 0 diverged after t = 0" in proc.stderr and "shear angle (rad)" in proc.stderr
    run = read_sheet_run(out)
    (diverged,) = run.meta["diverged"]
    assert run.complete and run.probes["t"].max() <= diverged["time_s"] < 0.1
    # frames.npy holds NaN from the stop on; the reader gives the frames the sheet reached
    stored = np.load(out / "frames.npy")
    assert np.isnan(stored[len(run.frames) :]).all() and len(run.frames) < len(stored)
    assert np.isfinite(run.frames).all() and run.frame_times[-1] <= diverged["time_s"]
