"""Sweeps: expansion, batching, results equal to single runs, resume after a real kill."""

import copy
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
import tomli_w
from conftest import overrides, run_cli

import warpcloth as wc
from warpcloth.scene import apply_overrides, expand, load_sweep, read_scene_file
from warpcloth.sweeps import run_sweep

D1 = "material.hysteresis_d1_gf_cm_per_cm"
GAMMA = "damping.gamma_per_s"
ALPHA = "material.hysteresis_alpha_cm"


def base(**fields):
    """Short damped swing (0.2 s hold, 0.3 s record) as raw scene data."""
    fields = dict(release__settle_time_s=0.2, release__move_time_s=0.1, run__duration_s=0.3) | fields
    return apply_overrides(read_scene_file("damped_swing"), overrides(**fields))


def with_sweep(raw, **spec):
    raw = copy.deepcopy(raw)
    raw["sweep"] = spec
    return raw


def test_expansion_is_grid_times_zip_times_random_and_deterministic():
    raw = with_sweep(
        base(),
        seed=7,
        grid={D1: [0.0, 0.04], "strip.width_mm": [30.0, 40.0, 50.0]},
        zip={GAMMA: [0.1, 0.2], "clamp.rotation_centre_dy_mm": [0.0, 1.0]},
        random={"method": "uniform", "samples": 4, "ranges": {ALPHA: [2.0, 8.0]}},
    )
    a, b = expand(raw), expand(raw)
    assert len(a.scenes) == 2 * 3 * 2 * 4
    assert a.assignments == b.assignments and a.fingerprint == b.fingerprint
    assert a.keys == [D1, "strip.width_mm", GAMMA, "clamp.rotation_centre_dy_mm", ALPHA]
    assert a.assignments[0][D1] == 0.0 and a.assignments[-1][D1] == 0.04  # grid is the outer loop
    assert [s.material.hysteresis_alpha_cm for s in a.scenes[:4]] == [v[ALPHA] for v in a.assignments[:4]]
    other = expand(with_sweep(raw, **(raw["sweep"] | {"seed": 8})))
    assert other.assignments != a.assignments


def test_a_scenes_plain_dict_is_dataclasses_asdict_value_for_value_and_type_for_type():
    # Scene.to_dict is taken several times a variant (batch keys, the fingerprint, the
    # records), so it skips asdict's generic deep copy; what it gives must not differ,
    # down to a tuple staying a tuple and an int an int (the fingerprint hashes its JSON).
    import dataclasses

    def typed(x):
        if isinstance(x, dict):
            return {k: typed(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [type(x).__name__, *(typed(v) for v in x)]
        return type(x).__name__, repr(x)

    scenes = [wc.load_scene(name) for name in ("damped_swing", "impulsive_rotation", "damped_swing_paper")]
    scenes += list(load_sweep("damped_swing_sweep", ["sweep.random.samples=4"]).scenes)
    for scene in scenes:
        assert typed(scene.to_dict()) == typed(dataclasses.asdict(scene))


def test_latin_hypercube_puts_one_sample_in_every_stratum():
    n = 50
    sweep = expand(
        with_sweep(
            base(),
            seed=3,
            random={"method": "latin_hypercube", "samples": n, "ranges": {D1: [0.0, 0.1], GAMMA: [1.0, 3.0]}},
        )
    )
    d1 = np.array([a[D1] for a in sweep.assignments])
    gamma = np.array([a[GAMMA] for a in sweep.assignments])
    assert sorted(np.floor(d1 / 0.1 * n).astype(int)) == list(range(n))
    assert sorted(np.floor((gamma - 1.0) / 2.0 * n).astype(int)) == list(range(n))


def test_the_latin_hypercube_is_scipys_and_fills_the_box_more_evenly_than_uniform():
    from scipy.stats import qmc

    spec = {"method": "latin_hypercube", "samples": 40, "ranges": {D1: [0.0, 0.1], GAMMA: [1.0, 3.0]}}
    sweep = expand(with_sweep(base(), seed=5, random=spec))
    expected = qmc.LatinHypercube(2, rng=np.random.default_rng(5)).random(40) * [0.1, 2.0] + [0.0, 1.0]
    np.testing.assert_array_equal([[a[D1], a[GAMMA]] for a in sweep.assignments], expected)
    uniform = expand(with_sweep(base(), seed=5, random=spec | {"method": "uniform"}))
    assert sweep.discrepancy == pytest.approx(qmc.discrepancy((expected - [0.0, 1.0]) / [0.1, 2.0]), rel=1e-12)
    assert sweep.discrepancy < uniform.discrepancy
    assert small_sweep().discrepancy is None  # no random block


def test_a_format_1_latin_hypercube_sweep_is_read_by_its_stored_variants_and_not_resumed(tmp_path):
    # Format 1 drew its Latin hypercube with warpcloth's own sampler; the same seed now
    # draws others. Stand-in for such a directory: a format-2 one whose sweep.json loses
    # its format and names another seed, so expanding it again gives other variants.
    raw = with_sweep(base(run__duration_s=0.05), seed=11, random={"samples": 3, "ranges": {D1: [0.0, 0.08]}})
    out = tmp_path / "old"
    run_sweep(expand(raw), out, workers=0, frames=True, probes="all")
    manifest = out / "sweep.json"
    info = json.loads(manifest.read_text())
    assert info["format"] == 2 and info["discrepancy"] == expand(raw).discrepancy
    info.pop("format")
    info["sweep"]["seed"] = 12
    manifest.write_text(json.dumps(info))
    recording = wc.load_recording(out)
    stored = pd.read_csv(out / "variants.csv")
    np.testing.assert_array_equal(recording.parameters[D1], stored[D1])  # the variants that ran
    assert [s.material.hysteresis_d1_gf_cm_per_cm for s in recording.scenes] == stored[D1].tolist()
    renamed = with_sweep(raw, **(raw["sweep"] | {"seed": 12}))
    with pytest.raises(
        wc.ArgumentError,
        match=r"^out: .*old was written by an older warpcloth \(sweep format 1\), "
        r"whose Latin hypercube drew other variants from the same seed; choose a new --out",
    ):
        run_sweep(expand(renamed), out, workers=0)
    info["format"] = 2  # a format-2 directory that no longer matches is refused, not relabelled
    manifest.write_text(json.dumps(info))
    with pytest.raises(wc.DataFileError, match="no longer resolve to the scenes that were simulated"):
        wc.load_recording(out)


def test_batch_level_fields_make_separate_batches():
    sweep = expand(with_sweep(base(), zip={"strip.spacing_mm": [5.0, 2.5, 5.0, 2.5, 5.0], GAMMA: [0, 1, 2, 3, 4]}))
    batches = sweep.batches(max_batch=2)
    assert batches == [[0, 2], [4], [1, 3]]


@pytest.mark.parametrize(
    "spec, field, text",
    [
        ({}, "sweep", "no [sweep] section with a grid"),
        ({"gird": {D1: [0.0]}}, "sweep", "no [sweep] section"),
        ({"grid": {D1: [0.0]}, "gird": {}}, "sweep.gird", "unknown field"),
        ({"grid": {"material.colour": [1.0]}}, 'sweep.grid."material.colour"', "is not a scene field"),
        ({"grid": {D1: []}}, f'sweep.grid."{D1}"', "non-empty list"),
        ({"grid": {D1: 0.04}}, f'sweep.grid."{D1}"', "non-empty list"),
        ({"zip": {D1: [0.0, 0.1], GAMMA: [1.0]}}, "sweep.zip", "equal lengths"),
        ({"grid": {D1: [0.0]}, "zip": {D1: [0.1]}}, f'sweep."{D1}"', "more than one block"),
        ({"random": {"samples": 0, "ranges": {D1: [0, 1]}}}, "sweep.random.samples", "positive integer"),
        ({"random": {"samples": 5, "ranges": {D1: [1.0, 0.5]}}}, f'sweep.random.ranges."{D1}"', "must be above"),
        ({"random": {"samples": 5, "ranges": {D1: [0.0, "x"]}}}, f'sweep.random.ranges."{D1}"', "finite number"),
        ({"random": {"samples": 5, "method": "sobol", "ranges": {D1: [0, 1]}}}, "sweep.random.method", "one of"),
        ({"random": {"samples": 5, "ranges": {D1: [0, 1]}}, "seed": -1}, "sweep.seed", "non-negative"),
        (
            {"grid": {D1: [0.04, -0.01]}},
            "material.hysteresis_d1_gf_cm_per_cm",
            f"in sweep variant 1 ({D1}=-0.01): must be ≥ 0",
        ),
    ],
)
def test_bad_sweep_specs(spec, field, text):
    with pytest.raises(wc.SceneError) as info:
        expand(with_sweep(base(), **spec))
    assert info.value.field == field and text in str(info.value)


def small_sweep():
    return expand(with_sweep(base(), grid={D1: [0.0, 0.04, 0.08]}, zip={GAMMA: [0.2, 2.0]}))


def test_sweep_results_equal_single_runs(tmp_path):
    sweep = small_sweep()
    summary = run_sweep(sweep, tmp_path / "s", max_batch=4, workers=0, probes="all")
    assert len(summary) == 6 and summary["batch"].nunique() == 2
    probes = pd.read_parquet(tmp_path / "s" / "probes")
    for i, scene in enumerate(sweep.scenes):
        single = wc.simulate(scene)
        mine = probes[probes.variant == i].sort_values("t")
        np.testing.assert_array_equal(mine["t"], single.t)
        for name in ("tip_x", "laser_x", "hysteresis_work", "damping_work"):
            np.testing.assert_array_equal(mine[name], single.probe(name, 0))
        assert summary.loc[i, "damping_work_J"] == single.probe("damping_work", 0)[-1]
        # the run alone measures itself as the sweep's summary does (wc.simulate's metrics)
        for name in ("first_period_s", "mean_log_decrement", "peak_tip_speed_m_per_s", "hysteresis_work_J"):
            np.testing.assert_equal(single.metrics.loc[0, name], summary.loc[i, name], err_msg=name)
    # by default a sweep keeps the probes its summary is measured from, the same values
    # losslessly, and the same summary; --probes none keeps the summary alone
    for kept, columns in (("summary", ["variant", "t", "laser_x", "tip_x"]), ("none", None)):
        smaller = run_sweep(sweep, tmp_path / kept, max_batch=4, workers=0, probes=kept)
        pd.testing.assert_frame_equal(smaller, summary, check_exact=True)
        if columns is None:
            assert not any((tmp_path / kept / "probes").iterdir())
            continue
        stored = pd.read_parquet(tmp_path / kept / "probes")
        assert list(stored.columns) == columns
        pd.testing.assert_frame_equal(stored, probes[columns], check_exact=True)
        assert json.loads((tmp_path / kept / "sweep.json").read_text())["probes"] == kept
    with pytest.raises(wc.ArgumentError, match="keeps 'summary' probes, not 'all': resume it with --probes summary"):
        run_sweep(sweep, tmp_path / "summary", workers=0, probes="all")
    with pytest.raises(wc.ArgumentError, match="^probes: 'some' is not one of summary, all, none$"):
        run_sweep(sweep, tmp_path / "x", workers=0, probes="some")
    # stronger damping dissipates more and decays faster
    assert (
        summary[summary[GAMMA] == 2.0]["damping_work_J"].values
        > summary[summary[GAMMA] == 0.2]["damping_work_J"].values
    ).all()


def test_a_diverged_variant_is_recorded_and_the_sweep_goes_on(tmp_path):
    raw = with_sweep(
        base(integrator__scheme="forward", integrator__dt_s=2e-5, release__enabled=False),
        zip={GAMMA: [0.0, 400.0], "material.tensile_gf_per_cm": [[2000.0, 0, 0, 2.93e7], [20.0, 0, 0, 0]]},
    )
    summary = run_sweep(expand(raw), tmp_path / "d", workers=0)
    assert summary["diverged"].tolist() == [True, False]
    assert summary.loc[0, "diverged_quantity"] == "tensile strain" and summary.loc[0, "diverged_time_s"] > 0
    assert summary.loc[0, "diverged_phase"] == "record"


def test_a_changed_sweep_does_not_resume_into_an_old_directory(tmp_path):
    run_sweep(small_sweep(), tmp_path / "s", workers=0)
    changed = expand(with_sweep(base(), grid={D1: [0.0, 0.05]}))
    with pytest.raises(wc.ArgumentError, match="^out: .*holds a different sweep"):
        run_sweep(changed, tmp_path / "s", workers=0)


def cli_sweep(scene_file, out, *extra):
    return [sys.executable, "-m", "warpcloth.cli", "sweep", str(scene_file), "--out", str(out), "--no-progress", *extra]


def read_results(out):
    summary = pd.read_parquet(out / "summary.parquet")
    probes = pd.read_parquet(out / "probes").sort_values(["variant", "t"]).reset_index(drop=True)
    return summary, probes


def test_resume_after_the_process_is_killed(tmp_path):
    scene_file = tmp_path / "sweep.toml"
    raw = with_sweep(base(run__duration_s=0.6), grid={D1: [0.0, 0.02, 0.04, 0.06]}, zip={GAMMA: [0.1, 1.0]})
    scene_file.write_text(tomli_w.dumps(raw))
    reference = tmp_path / "reference"
    assert run_cli(*cli_sweep(scene_file, reference, "--workers", "0", "--max-batch", "1")[3:]).returncode == 0

    out = tmp_path / "killed"
    child = subprocess.Popen(cli_sweep(scene_file, out, "--workers", "0", "--max-batch", "1"))
    deadline = time.time() + 120
    while time.time() < deadline and len(list((out / "summary").glob("batch-*.parquet"))) < 2:
        time.sleep(0.05)
    os.kill(child.pid, signal.SIGKILL)  # a real kill: no cleanup runs
    child.wait()
    kept = {p.name: p.stat().st_mtime_ns for p in (out / "summary").glob("batch-*.parquet")}
    assert 2 <= len(kept) < 8, "the kill should land mid-sweep"
    assert not (out / "summary.parquet").exists()

    assert run_cli(*cli_sweep(scene_file, out, "--workers", "0", "--max-batch", "1")[3:]).returncode == 0
    # only the missing batches ran: the finished ones were not rewritten
    assert all((out / "summary" / name).stat().st_mtime_ns == t for name, t in kept.items())
    assert not list(out.rglob("*.tmp"))
    for mine, theirs in zip(read_results(out), read_results(reference), strict=True):
        pd.testing.assert_frame_equal(mine, theirs)


def test_threads_give_the_serial_results_bit_for_bit(tmp_path):
    # batches on 1, 2 and 3 threads of this process against one after another
    sweep = small_sweep()
    run_sweep(sweep, tmp_path / "serial", max_batch=2, workers=0)
    for threads in (1, 2, 3):
        run_sweep(sweep, tmp_path / f"t{threads}", max_batch=2, workers=threads)
        for mine, theirs in zip(read_results(tmp_path / f"t{threads}"), read_results(tmp_path / "serial"), strict=True):
            pd.testing.assert_frame_equal(mine, theirs, check_exact=True)


@pytest.mark.slow
def test_scheduler_and_workers_as_processes_survive_a_killed_worker(tmp_path):
    # A scheduler and two workers started as separate processes on loopback; one worker
    # is killed once results start arriving. Dask reruns its batch elsewhere; results
    # must equal a single-process run.
    scene_file = tmp_path / "sweep.toml"
    raw = with_sweep(base(run__duration_s=0.6), grid={D1: [0.0, 0.02, 0.04, 0.06]}, zip={GAMMA: [0.1, 1.0]})
    scene_file.write_text(tomli_w.dumps(raw))
    run_sweep(load_sweep(scene_file), tmp_path / "serial", max_batch=1, workers=0)

    env = os.environ | {"DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    bin_dir = os.path.dirname(sys.executable)
    scheduler_file = tmp_path / "scheduler.json"
    procs = [
        subprocess.Popen(
            [
                os.path.join(bin_dir, "dask"),
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(scheduler_file),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env=env,
        )
    ]
    try:
        deadline = time.time() + 60
        while not scheduler_file.exists() and time.time() < deadline:
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [
                        os.path.join(bin_dir, "dask"),
                        "worker",
                        address,
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--no-nanny",
                        "--no-dashboard",
                    ],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                    env=env,
                )
            )
        out = tmp_path / "dask"
        driver = subprocess.Popen(
            cli_sweep(scene_file, out, "--max-batch", "1", "--scheduler", address),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        while time.time() < deadline + 120 and not list((out / "summary").glob("batch-*.parquet")):
            time.sleep(0.05)
        procs[1].kill()  # a worker dies mid-sweep
        assert len(list((out / "summary").glob("batch-*.parquet"))) < 8
        stdout, stderr = driver.communicate(timeout=300)
        assert driver.returncode == 0, stderr
        for mine, theirs in zip(read_results(out), read_results(tmp_path / "serial"), strict=True):
            pd.testing.assert_frame_equal(mine, theirs)
    finally:
        for p in procs:
            p.kill()


def test_overrides_reach_the_base_scene_and_the_sweep_options():
    sweep = load_sweep("damped_swing_sweep", ["sweep.random.samples=12", "sweep.seed=5", "run.duration_s=0.5"])
    assert len(sweep.scenes) == 12 and all(s.run.duration_s == 0.5 for s in sweep.scenes)
    assert sweep.assignments != load_sweep("damped_swing_sweep", ["sweep.random.samples=12"]).assignments


def test_a_variant_that_diverges_during_the_hold_does_not_stop_the_sweep(tmp_path):
    # A tensile curve so soft that gravity stretches the strip past divergence_strain while
    # it is held: no sample after t = 0 exists for it, and the sweep still completes.
    tensile = [[2000.0, 0.0, 0.0, 2.93e7], [0.5, 0.0, 0.0, 0.0]]
    sweep = wc.expand(
        {
            "run": {"duration_s": 0.05},
            "release": {"enabled": True, "settle_time_s": 0.05},
            "sweep": {"zip": {"material.tensile_gf_per_cm": tensile}},
        }
    )
    summary = wc.run_sweep(sweep, tmp_path / "s", workers=0)
    healthy, soft = summary.iloc[0], summary.iloc[1]
    assert not healthy["diverged"] and healthy["hysteresis_work_J"] > 0
    assert soft["diverged"] and soft["diverged_time_s"] < 0 and soft["diverged_quantity"] == "tensile strain"
    assert soft["diverged_phase"] == "move"  # gravity stretches it past the limit as it is carried
    assert np.isnan(soft["hysteresis_work_J"]) and np.isnan(soft["first_period_s"]) and soft["n_half_cycles"] == 0
