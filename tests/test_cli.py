"""The command line and the run directory it writes; the packaging of kernels/scenes."""

import csv
import json
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import warp as wp
from conftest import interruptible, run_cli
from warpcloth.kernels import PROBE_FIELDS

import warpcloth as wc
from warpcloth import load_recording


def warpcloth_cli(*args, cwd):
    return run_cli(*args, cwd=cwd)


def test_run_writes_a_complete_run_directory(tmp_path):
    out = tmp_path / "swing"
    done = warpcloth_cli(
        "run",
        "damped_swing",
        "--out",
        str(out),
        "--set",
        "run.duration_s=0.8",
        "--set",
        "release.settle_time_s=0.2",
        "--no-progress",
        "--usd",
        "swing.usda",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert "endTimeCode = 48" in (tmp_path / "swing.usda").read_text()  # 49 frames
    assert "first period 0.5" in done.stdout and "turning points" in done.stdout
    meta = json.loads((out / "meta.json").read_text())
    assert meta["complete"] and meta["diverged"] == [] and meta["n_variants"] == 1
    with open(out / "probes.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", "variant", *PROBE_FIELDS]
    t = np.array([float(r[0]) for r in rows[1:]])
    assert len(t) == 481 and t[0] == 0.0 and t[-1] == pytest.approx(0.8)
    frames = np.load(out / "frames.npy")
    times = np.load(out / "frame_times.npy")
    assert frames.shape == (49, 1, 25, 2) and times.shape == (49,)
    # the file agrees with the API on the same scene
    scene = wc.load_scene(out / "scene.toml")
    assert scene.run.duration_s == 0.8 and scene.release.settle_time_s == 0.2
    api = wc.simulate(scene)
    np.testing.assert_array_equal(frames, api.frames)
    tip = np.array([float(r[2]) for r in rows[1:]])
    np.testing.assert_array_equal(tip, api.probe("tip_x", 0))


def test_bad_scene_is_a_clear_error_before_running(tmp_path):
    done = warpcloth_cli(
        "run", "damped_swing", "--set", "strip.spacing_mm=-1", "--out", str(tmp_path / "x"), cwd=tmp_path
    )
    assert done.returncode == 2
    assert "strip.spacing_mm: must be > 0, got -1" in done.stderr
    assert not (tmp_path / "x").exists()


def test_divergence_is_reported_and_the_record_kept(tmp_path):
    out = tmp_path / "fwd"
    done = warpcloth_cli(
        "run",
        "damped_swing",
        "--out",
        str(out),
        "--no-progress",
        "--set",
        "integrator.scheme=forward",
        "--set",
        "integrator.dt_s=2e-5",
        "--set",
        "release.enabled=false",
        "--set",
        "damping.gamma_per_s=0",
        cwd=tmp_path,
    )
    assert done.returncode == 3
    assert "strip 0 diverged after t = 0, at t =" in done.stderr and "tensile strain" in done.stderr
    meta = json.loads((out / "meta.json").read_text())
    assert meta["diverged"][0]["quantity"] == "tensile strain"
    body = (out / "probes.csv").read_text().splitlines()[1:]
    assert body and "nan" not in "\n".join(body).lower()  # rows stop at the divergence


def test_wheel_maps_kernels_and_scenes_into_the_warpcloth_namespace(tmp_path):
    # kernels/ must not install as a top-level "kernels" (a different PyPI package).
    root = wc.__file__.rsplit("/warpcloth/", 1)[0]
    done = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path), root],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    (wheel,) = tmp_path.glob("warpcloth-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    # every module of the source tree is in the wheel (a subpackage missing from
    # pyproject's list would install a package that cannot import itself)
    root_path = Path(root)
    sources = {
        f"warpcloth/{p.relative_to(root_path / 'warpcloth').as_posix()}"
        for p in (root_path / "warpcloth").rglob("*.py")
    }
    sources |= {
        f"warpcloth/kernels/{p.relative_to(root_path / 'kernels').as_posix()}"
        for p in (root_path / "kernels").rglob("*.py")
    }
    assert sources - set(names) == set()
    assert "warpcloth/kernels/strip.py" in names and "warpcloth/calibrate/kes/readers.py" in names
    assert "warpcloth/scenes/damped_swing.toml" in names and "warpcloth/scenes/impulsive_rotation.toml" in names
    assert not any(n.startswith("kernels/") or n.startswith("scenes/") for n in names)
    # the data files too (one wheel build serves both checks: it takes ~5 s)
    for name in wc.scene.bundled_materials():
        assert f"warpcloth/scenes/materials/{name}.toml" in names
    for name in ("kes_fb1_example", "kes_fb2_example", "kes_fb2_inner_loops"):
        assert f"warpcloth/scenes/data/{name}.csv" in names


def test_progress_bar_shows_simulated_time_rate_and_eta(capsys):
    scene = wc.load_scene("impulsive_rotation", ["run.duration_s=0.05"])
    wc.simulate(scene, progress=True)
    err = capsys.readouterr().err
    assert "0.050/0.050 s sim" in err and "strip-steps/s" in err and "<" in err  # elapsed<remaining


@pytest.mark.parametrize(
    "args, message",
    [
        (("sweep", "damped_swing_sweep", "--max-batch", "0"), "argument --max-batch: 0 must be at least 1"),
        (("sweep", "damped_swing_sweep", "--workers", "-1"), "argument --workers: -1 must be at least 0"),
        (("plot", "runs/x", "--times", "nan"), "argument --times: 'nan' is not a finite number"),
        (
            ("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--align-start", "inf"),
            "argument --align-start: 'inf' is not a finite number",
        ),
        (("render", "runs/x", "--stride", "0"), "argument --stride: 0 must be at least 1"),
        (
            ("run", "impulsive_rotation", "--device", "gpu7"),
            "argument --device: 'gpu7' is not a device of this machine",
        ),
        (("run", "impulsive_rotation", "--usd", "stage.txt"), "--usd: stage.txt must end in one of .usd, .usda, .usdc"),
    ],
)
def test_bad_options_are_refused_before_anything_runs(tmp_path, args, message):
    done = warpcloth_cli(*args, "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()  # refused before any directory or kernel


def test_an_unwritable_output_is_one_line_not_a_traceback(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    done = warpcloth_cli(
        "run",
        "impulsive_rotation",
        "--set",
        "run.duration_s=0.01",
        "--no-progress",
        "--out",
        str(blocker / "run"),
        cwd=tmp_path,
    )
    assert done.returncode == 5 and "I/O error: Not a directory" in done.stderr and "Traceback" not in done.stderr
    assert str(blocker / "run") in done.stderr or str(blocker) in done.stderr


def run_files(directory):
    return {p.relative_to(directory): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def test_an_existing_run_is_never_replaced_silently(tmp_path):
    out = tmp_path / "swing"
    first = ("run", "impulsive_rotation", "--set", "run.duration_s=0.02", "--no-progress", "--out", str(out))
    assert warpcloth_cli(*first, cwd=tmp_path).returncode == 0
    before = run_files(out)
    again = warpcloth_cli(
        "run", "impulsive_rotation", "--set", "run.duration_s=0.03", "--no-progress", "--out", str(out), cwd=tmp_path
    )
    assert again.returncode == 2 and f"--out: {out} already holds a run" in again.stderr
    assert run_files(out) == before  # untouched, byte for byte
    with pytest.raises(wc.ArgumentError, match="^out: .* already holds a run"):
        wc.simulate(wc.load_scene("impulsive_rotation"), out=out)
    sweep = warpcloth_cli("sweep", "damped_swing_sweep", "--out", str(out), "--workers", "0", cwd=tmp_path)
    assert sweep.returncode == 2 and "already holds a run" in sweep.stderr
    replaced = warpcloth_cli(
        "run",
        "impulsive_rotation",
        "--set",
        "run.duration_s=0.03",
        "--no-progress",
        "--out",
        str(out),
        "--overwrite",
        cwd=tmp_path,
    )
    assert replaced.returncode == 0, replaced.stderr
    assert wc.load_scene(out / "scene.toml").run.duration_s == 0.03
    assert json.loads((out / "meta.json").read_text())["complete"]
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no staging left


def test_a_killed_overwrite_leaves_the_old_run_whole(tmp_path):
    # A real SIGKILL while the replacing run is streaming: the old run is byte-identical,
    # the new one sits only in a hidden staging directory marked incomplete.
    out = tmp_path / "swing"
    assert (
        warpcloth_cli(
            "run",
            "impulsive_rotation",
            "--set",
            "run.duration_s=0.02",
            "--no-progress",
            "--out",
            str(out),
            cwd=tmp_path,
        ).returncode
        == 0
    )
    before = run_files(out)
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "warpcloth.cli",
            "run",
            "damped_swing",
            "--set",
            "run.duration_s=600",
            "--no-progress",
            "--out",
            str(out),
            "--overwrite",
        ],
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 120
        staging = []
        while time.monotonic() < deadline and not staging:
            staging = [
                p
                for p in tmp_path.iterdir()
                if p.name.startswith(".swing.new-")
                and (p / "probes.csv").is_file()
                and (p / "probes.csv").stat().st_size > 1000
            ]
            time.sleep(0.2)
        assert staging, "the replacing run never started streaming"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    assert run_files(out) == before
    assert json.loads((staging[0] / "meta.json").read_text())["complete"] is False


def test_result_files_are_refused_when_present_unless_overwrite(tmp_path):
    # A fitted scene, a material file and a USD stage are results too: an existing one
    # is refused before any work, and --overwrite replaces it (atomically).
    run = ("run", "impulsive_rotation", "--set", "run.duration_s=0.02", "--no-progress", "--out", "r")
    assert warpcloth_cli(*run, cwd=tmp_path).returncode == 0
    commands = {
        "stage.usda": ("export-usd", "r", "-o", "stage.usda"),
        "mat.toml": (
            "material",
            "fit-kes",
            "--tensile",
            "kes_fb1_example",
            "--bending",
            "kes_fb2_example",
            "-o",
            "mat.toml",
            "--density-g-per-cm2",
            "2.03e-2",
        ),
        "fitted.toml": (
            "clamp",
            "fit-angle",
            "impulsive_rotation_encoder",
            "--scene",
            "impulsive_rotation",
            "-o",
            "fitted.toml",
        ),
    }
    for name, command in commands.items():
        (tmp_path / name).write_text("a result someone kept\n")
        refused = warpcloth_cli(*command, cwd=tmp_path)
        assert refused.returncode == 2 and f"{name} already exists" in refused.stderr, refused.stderr
        assert (tmp_path / name).read_text() == "a result someone kept\n"
        done = warpcloth_cli(*command, "--overwrite", cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        assert (tmp_path / name).read_text() != "a result someone kept\n"


def test_a_torn_tail_is_never_read_as_data(tmp_path):
    # A kill (or a full disk) in the middle of appending rows leaves a partial tail after
    # the last commit; "…e-05" cut to "…e-0" or "1.23" would read as a wrong number, not
    # as missing data. Readers parse only what meta.json records as committed.
    out = tmp_path / "r"
    wc.simulate(wc.load_scene("impulsive_rotation", ["run.duration_s=0.02"]), out=out)
    whole = load_recording(out).probes
    probes, meta_file = out / "probes.csv", out / "meta.json"
    meta = json.loads(meta_file.read_text())
    assert meta["committed"]["probe_rows"] == len(whole) and meta["committed"]["probe_bytes"] == probes.stat().st_size
    text = probes.read_text()
    with open(probes, "a") as fh:
        fh.write(text.splitlines()[-1][:-9])  # a row written after the last commit, cut inside a number
    with pytest.raises(wc.DataFileError, match="bytes but meta.json records .* the file was truncated or changed"):
        load_recording(out)
    meta_file.write_text(json.dumps(meta | {"complete": False}))
    partial = load_recording(out).probes
    pd.testing.assert_frame_equal(partial.reset_index(drop=True), whole.reset_index(drop=True))
    probes.write_text(text[: len(text) - 9])  # shorter than what was committed: damaged, not interrupted
    with pytest.raises(wc.DataFileError, match="is shorter .* than its committed part"):
        load_recording(out)


def test_ctrl_c_is_one_line_and_keeps_what_was_written(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "warpcloth.cli",
            "run",
            "damped_swing",
            "--set",
            "run.duration_s=600",  # interrupted long before its end, on however loaded a machine
            "--no-progress",
            "--out",
            str(out),
        ],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )

    def committed_frames():
        try:
            return json.loads((out / "meta.json").read_text())["committed"]["frames"]
        except (OSError, ValueError, KeyError):
            return 0

    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and committed_frames() == 0:  # stop it once it has recorded something
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in stderr, stderr
    assert f"interrupted; what was written so far is kept in {out} and marked incomplete" in stderr
    assert json.loads((out / "meta.json").read_text())["complete"] is False
    assert len(load_recording(out).probes) > 0  # the interrupted run reads back up to where it stopped


@pytest.mark.parametrize("damage", ["meta.json torn", "meta.json missing"])
def test_a_damaged_run_directory_is_named_not_a_traceback(tmp_path, damage):
    out = tmp_path / "r"
    wc.simulate(wc.load_scene("impulsive_rotation", ["run.duration_s=0.02"]), out=out)
    (out / "sweep.json").unlink(missing_ok=True)
    if damage == "meta.json torn":
        (out / "meta.json").write_text((out / "meta.json").read_text()[:40])
        with pytest.raises(wc.DataFileError, match=r"meta.json: is damaged \(not valid JSON"):
            load_recording(out)
    else:
        (out / "meta.json").unlink()
        (out / "probes.csv").touch()
    done = warpcloth_cli("plot", str(out), cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr and str(out) in done.stderr, done.stderr


def test_version_provenance_and_dict_overrides(tmp_path):
    done = warpcloth_cli("--version", cwd=tmp_path)
    assert done.returncode == 0 and done.stdout.startswith("warpcloth ")
    result = wc.run(
        "damped_swing",
        {
            "damping.gamma_per_s": 0.5,
            "run.duration_s": 0.05,
            "release.settle_time_s": 0.05,
            "clamp.edge_hinge": "paper",
        },
        out=tmp_path / "r",
    )
    assert result.scenes[0].damping.gamma_per_s == 0.5 and result.scenes[0].clamp.edge_hinge == "paper"
    provenance = json.loads((tmp_path / "r" / "meta.json").read_text())["provenance"]
    assert provenance["warp"] == wp.__version__ and provenance["device"] == "cpu" and provenance["date_utc"]
    with pytest.raises(TypeError, match="not one string"):
        wc.run("damped_swing", "run.duration_s=0.1")
    sweep = wc.expand({"run": {"duration_s": 0.02}, "sweep": {"grid": {"damping.gamma_per_s": [0.1]}}})
    wc.run_sweep(sweep, tmp_path / "s", workers=0, progress=False)
    assert json.loads((tmp_path / "s" / "sweep.json").read_text())["provenance"]["numpy"] == np.__version__


def test_scene_list_and_show_give_templates_that_run(tmp_path):
    listed = warpcloth_cli("scene", "list", cwd=tmp_path)
    assert listed.returncode == 0 and "damped_swing: Paper §3.1 experiment (a)" in listed.stdout
    shown = warpcloth_cli("scene", "show", "impulsive_rotation", cwd=tmp_path)
    assert shown.returncode == 0 and shown.stdout.startswith("# Paper §3.1 experiment (b)")
    assert warpcloth_cli("scene", "show", "damped_swing", "-o", "mine.toml", cwd=tmp_path).returncode == 0
    assert wc.load_scene(tmp_path / "mine.toml") == wc.load_scene("damped_swing")
    again = warpcloth_cli("scene", "show", "damped_swing", "-o", "mine.toml", cwd=tmp_path)
    assert again.returncode == 2 and "already exists" in again.stderr
    assert "no bundled scene 'nope'" in warpcloth_cli("scene", "show", "nope", cwd=tmp_path).stderr


def test_results_as_xarray_and_dataframe(tmp_path):
    sweep = wc.expand({"run": {"duration_s": 0.05}, "sweep": {"grid": {"damping.gamma_per_s": [0.1, 0.3]}}})
    wc.run_sweep(sweep, tmp_path / "s", workers=0, frames=True, probes="all", progress=False)
    recording = wc.load_recording(tmp_path / "s")
    ds = recording.to_xarray()
    assert list(ds["damping.gamma_per_s"].values) == [0.1, 0.3] and ds["tip_x"].attrs["units"] == "m"
    probes = recording.probes[recording.probes["variant"] == 1].sort_values("t")
    np.testing.assert_array_equal(ds["tip_x"].sel(variant=1).values, probes["tip_x"].to_numpy())
    np.testing.assert_array_equal(ds["frames"].values, recording.frames)
    table = recording.to_dataframe()
    assert set(table.groupby("damping.gamma_per_s")["variant"].first()) == {0, 1}


def test_a_result_in_memory_and_its_run_directory_give_the_same_dataset(tmp_path):
    # RunResult.to_xarray (in memory) and Recording.to_xarray (read back) share one layout
    scenes = [wc.load_scene("damped_swing", {"run.duration_s": 0.1, "damping.gamma_per_s": g}) for g in (0.2, 0.7)]
    result = wc.simulate(scenes, out=tmp_path / "run")
    memory, disk = result.to_xarray(), wc.load_recording(tmp_path / "run").to_xarray()
    assert list(memory["damping.gamma_per_s"].values) == [0.2, 0.7]
    for name in ("tip_x", "laser_x", "kinetic", "frames"):
        np.testing.assert_allclose(memory[name].values, disk[name].values, rtol=1e-15, atol=0)
    np.testing.assert_allclose(memory["t"].values, disk["t"].values, rtol=1e-15)
    assert memory.attrs["coordinates"] == disk.attrs["coordinates"] and "clamp edge" in disk.attrs["coordinates"]
    table = result.to_dataframe()
    assert len(table) == result.probes.shape[0] * 2 and set(table["damping.gamma_per_s"]) == {0.2, 0.7}
    np.testing.assert_array_equal(table[table["variant"] == 1]["tip_x"].to_numpy(), result.probe("tip_x", 1))


def test_an_empty_output_path_is_refused_not_defaulted(tmp_path):
    done = warpcloth_cli("run", "damped_swing", "--out", "", cwd=tmp_path)
    assert done.returncode == 2 and "argument --out: an empty path" in done.stderr
    assert not (tmp_path / "runs").exists()


def cli_options(parser=None, command=()):
    """(command, option, action) of every option of every ``warpcloth`` command."""
    import argparse

    from warpcloth.cli.app import parser as top

    parser = parser or top()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from cli_options(sub, (*command, name))
        elif action.option_strings:
            yield " ".join(command), action.option_strings[-1], action


def test_every_option_with_a_default_states_it_in_its_help():
    # flags (store_true) default to off, which needs no saying; an option whose default is
    # None or empty is either an input or says what its absence means (checked by hand)
    import argparse

    silent = [
        f"{command} {option} (default {action.default!r})"
        for command, option, action in cli_options()
        if not isinstance(action, (argparse._HelpAction, argparse._VersionAction, argparse._StoreTrueAction))
        and action.default not in (None, [], False)
        and "(default" not in (action.help or "")
    ]
    assert not silent, f"options whose help does not state their default: {silent}"


def test_fit_help_states_the_default_bounds(capsys):
    from warpcloth.calibrate.motion_fit import free_parameters
    from warpcloth.cli import main

    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "see README" not in text
    assert (
        "--bounds BOUNDS name=LOW:HIGH,... (default: a rotation centre or hold position ± 10 mm around the "
        "scene's value; gamma 0 to max(4× the scene's, 2 /s); a hysteresis amplitude D1, Ms or Mf 0 to 4×; any "
        "other ¼× to 4×"
    ) in text
    # and they are the bounds the fit takes
    scene = wc.load_scene(
        "impulsive_rotation", {"material.hysteresis_d1_gf_cm_per_cm": 0.04, "damping.gamma_per_s": 0.3}
    )
    bounds = {p.field: (p.lower, p.upper) for p in free_parameters("rotation_centre_dy_mm,gamma,D1,D", scene)}
    dy = scene.clamp.rotation_centre_dy_mm
    d = scene.material.bending_rigidity_gf_cm2_per_cm
    assert bounds == {
        "clamp.rotation_centre_dy_mm": (dy - 10, dy + 10),
        "damping.gamma_per_s": (0.0, 2.0),
        "material.hysteresis_d1_gf_cm_per_cm": (0.0, 0.16),
        "material.bending_rigidity_gf_cm2_per_cm": (d / 4, 4 * d),
    }
