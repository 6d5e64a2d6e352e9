"""Sweeps of sheet scenes: through the CLI into a sweep directory, each variant equal to
the same sheet run alone (bit for bit), resumed after an interruption, bad fields refused
where they were written, a diverging variant recorded as diverged."""

import numpy as np
import pandas as pd
import pytest
import tomli_w
from conftest import run_cli
from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS

from warpcloth.runs import simulate
from warpcloth.scene import load_sweep, read_scene_file
from warpcloth.scene.sheet_build import load_sheet_scene
from warpcloth.sweeps import marker_columns

G = "shear.rigidity_gf_per_cm_deg"
GAMMA = "damping.gamma_per_s"
SHORT = ("--set", "run.duration_s=0.1", "--set", "release.settle_time_s=0.05")


def sweep_file(tmp_path, name="sheet_sweep.toml", **changes):
    """The bundled shear_swing_sweep (10 mm, 17 G × 2 γ) written to a file, with changes."""
    raw = read_scene_file("shear_swing_sweep")
    for section, values in changes.items():
        raw[section] = raw.get(section, {}) | values
    path = tmp_path / name
    path.write_text(tomli_w.dumps(raw))
    return path


def sweep(scene, out, *extra):
    return run_cli("sweep", scene, "--out", out, "--no-progress", "--workers", "0", *SHORT, *extra)


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """The bundled sheet sweep, shortened, run once through the CLI in batches of 4 (the
    last of 2), keeping every probe."""
    out = tmp_path_factory.mktemp("sheet_sweep") / "s"
    done = sweep("shear_swing_sweep", out, "--max-batch", "4", "--probes", "all")
    assert done.returncode == 0, done.stderr
    return out, done


def test_a_sheet_sweep_runs_through_the_cli_into_a_sweep_directory(swept):
    out, done = swept
    assert "34 variants" in done.stdout and "0 diverged" in done.stdout
    assert "integrator.dt_s = auto, for 34 of the 34 variants" in done.stdout
    summary = pd.read_csv(out / "summary.csv")
    assert summary["variant"].tolist() == list(range(34)) and summary["batch"].tolist() == [v // 4 for v in range(34)]
    grid = read_scene_file("shear_swing_sweep")["sweep"]["grid"][G]
    assert len(grid) == 17 and sorted(set(zip(summary[G], summary[GAMMA], strict=True))) == sorted(
        (g, c) for g in grid for c in (0.1, 1.0)
    )
    assert not summary["diverged"].any()
    # the air's work grows with γ, the shear loop's with its hysteresis alone: neither is NaN
    low, high = summary[summary[GAMMA] == 0.1], summary[summary[GAMMA] == 1.0]
    assert (high["damping_work_J"].to_numpy() > 5 * low["damping_work_J"].to_numpy()).all()
    assert summary["hysteresis_work_J"].gt(0).all() and summary["energy_drift_relative"].lt(1e-3).all()
    probes = pd.read_parquet(out / "probes")
    assert list(probes.columns) == ["variant", "t", *SHEET_PROBE_FIELDS, *marker_columns(3)]
    # its summary plots as a strip sweep's; the views of single variants refuse it in one line
    plotted = run_cli("plot", out, "--metric", "peak_shear_angle_deg", "--x", G, "--out", out.parent / "fig")
    assert plotted.returncode == 0 and (out.parent / "fig" / f"peak_shear_angle_deg_vs_{G}.png").is_file()
    refused = run_cli("plot", out, "--out", out.parent / "figs")
    assert refused.returncode != 0 and len(refused.stderr.strip().splitlines()) == 1
    assert "is a sweep of sheet scenes" in refused.stderr
    # analyse measures a strip's swing: a sheet sweep is refused in one line (issue 39: a KeyError)
    analysed = run_cli("analyse", out)
    assert analysed.returncode == 2 and len(analysed.stderr.strip().splitlines()) == 1, analysed.stderr
    assert "is a sheet sweep: analyse measures a strip's swing" in analysed.stderr


def test_each_variant_equals_the_same_sheet_run_alone_bit_for_bit(swept):
    out, _ = swept
    summary = pd.read_parquet(out / "summary.parquet")
    probes = pd.read_parquet(out / "probes")
    variants = pd.read_csv(out / "variants.csv")
    expanded = load_sweep("shear_swing_sweep", SHORT[1::2])
    dt = expanded.scenes[0].integrator.dt_s
    assert {s.integrator.dt_s for s in expanded.scenes} == {dt}  # one step, chosen by auto for all
    for i in (0, 33):  # the first of a batch of four and the last of the last batch, of two
        row = variants.loc[i]
        scene = load_sheet_scene(
            "shear_swing_sweep",
            [*SHORT[1::2], f"{G}={row[G]}", f"{GAMMA}={row[GAMMA]}", f"integrator.dt_s={dt!r}"],
        )
        alone = simulate(scene)
        mine = probes[probes.variant == i].sort_values("t")
        np.testing.assert_array_equal(mine["t"], alone.t)
        for q, name in enumerate(SHEET_PROBE_FIELDS):
            np.testing.assert_array_equal(mine[name], alone.probes[:, q, 0])
        np.testing.assert_array_equal(mine[marker_columns(3)].to_numpy(), alone.markers[:, 0].reshape(len(alone.t), -1))
        for name, value in alone.metrics.loc[0].items():  # what the run alone measured of itself
            assert summary.loc[i, name] == value or (pd.isna(value) and pd.isna(summary.loc[i, name])), name


def test_a_resumed_sheet_sweep_runs_only_the_missing_batches_and_gives_the_same_summary(swept, tmp_path):
    import shutil

    reference, _ = swept
    out = tmp_path / "resumed"
    shutil.copytree(reference, out)
    # what a kill mid-sweep leaves (tests/test_sweep.py kills one for real): the second
    # batch's summary never written, a probe file of it on disk, nothing merged
    (out / "summary" / "batch-0001.parquet").unlink()
    for name in ("summary.parquet", "summary.csv"):
        (out / name).unlink()
    kept = (out / "summary" / "batch-0000.parquet").stat().st_mtime_ns
    done = sweep("shear_swing_sweep", out, "--max-batch", "4", "--probes", "all")
    assert done.returncode == 0, done.stderr
    assert (out / "summary" / "batch-0000.parquet").stat().st_mtime_ns == kept
    pd.testing.assert_frame_equal(
        pd.read_parquet(out / "summary.parquet"), pd.read_parquet(reference / "summary.parquet"), check_exact=True
    )
    assert (out / "summary.csv").read_text() == (reference / "summary.csv").read_text()


def line_of(path, text):
    return next(n for n, line in enumerate(path.read_text().splitlines(), 1) if text in line)


@pytest.mark.parametrize(
    "grid, field, says",
    [
        ({"shear.rigidity_gf_per_cm": [0.5]}, 'sweep.grid."shear.rigidity_gf_per_cm"', "is not a scene field"),
        ({G: [1.0, -0.5]}, G, f"in sweep variant 1 ({G}=-0.5): must be ≥ 0"),
        ({"clamp.axis_z": [1.0, 0.0]}, "clamp.axis_z", "in sweep variant 1 (clamp.axis_z=0.0)"),
    ],
)
def test_bad_sheet_sweep_fields_are_refused_in_one_line_naming_field_and_line(tmp_path, grid, field, says):
    scene = sweep_file(tmp_path)
    raw = read_scene_file(scene)
    raw["sweep"] = {"grid": grid}
    scene.write_text(tomli_w.dumps(raw))
    done = sweep(scene, tmp_path / "bad")
    line = line_of(scene, next(iter(grid)))
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert field in done.stderr and says in done.stderr and f"{scene}, line {line}" in done.stderr, done.stderr
    assert not (tmp_path / "bad").exists()


def test_a_fixed_step_above_a_variants_stability_estimate_is_refused_naming_it(tmp_path):
    # the base's step is stable; the variant with a 100× stiffer warp (a1) is not
    base = load_sheet_scene("shear_swing_sweep")
    stiff = "material.tensile_gf_per_cm.0"
    scene = sweep_file(tmp_path, integrator={"dt_s": 1.5 * base.integrator.dt_s})
    raw = read_scene_file(scene)
    a1 = raw.get("material", {}).get("tensile_gf_per_cm", load_sheet_scene(scene).material.tensile_gf_per_cm)[0]
    raw["sweep"] = {"grid": {stiff: [a1, 100 * a1]}}
    scene.write_text(tomli_w.dumps(raw))
    done = sweep(scene, tmp_path / "bad")
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "integrator.dt_s" in done.stderr and "in sweep variant 1" in done.stderr, done.stderr
    assert "stability estimate" in done.stderr


def test_a_diverging_variant_is_recorded_as_diverged_and_the_sweep_goes_on(tmp_path):
    # one translation piece, d = c t² for 50 ms: c = 4e5 mm/s² drags the top 1 m, and the
    # sheet's yarns stretch past the divergence strain
    scene = sweep_file(tmp_path)
    raw = read_scene_file(scene)
    raw["clamp"]["translation_segments"] = [{"t_start_s": 0.0, "t_end_s": 0.05, "d_coefficients_mm": [0.0, 0.0, 4e3]}]
    raw["sweep"] = {"zip": {"clamp.translation_segments.0.d_coefficients_mm.2": [4e3, 4e5]}}
    scene.write_text(tomli_w.dumps(raw))
    done = sweep(scene, tmp_path / "d")
    assert done.returncode == 0, done.stderr
    assert "1 diverged" in done.stdout and "1 sheet variant(s) diverged (1)" in done.stderr
    summary = pd.read_csv(tmp_path / "d" / "summary.csv")
    assert summary["diverged"].tolist() == [False, True]
    row = summary.loc[1]
    assert row["diverged_phase"] == "record" and 0 < row["diverged_time_s"] < 0.1
    assert row["diverged_quantity"] in ("tensile strain", "shear angle (rad)")
    metrics = [c for c in summary.columns if c.endswith(("_mm", "_deg", "_J", "_relative"))]
    assert summary.loc[1, metrics].isna().all() and summary.loc[0, metrics].notna().all()
