"""Real faults, not mocks: a full disk (a file-size limit set with setrlimit in the child,
which needs no root), a SIGKILL in the middle of streaming, and what each leaves behind.

The promise (README, "What warpcloth promises"): a full disk is exit 5 and one line; a
kill or a full disk leaves either the old result or a new one marked incomplete whose
committed part reads back exactly, never a torn file that reads as valid.
"""

import functools
import json
import re
import resource
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import interruptible, run_cli

import warpcloth as wc
from warpcloth.io.load import load_recording


@functools.cache
def kernels_compiled():
    """The scenes' kernels compiled into Warp's cache by this process: with a cold cache a
    file-size-limited child would meet its limit in Warp's precompiled header (a cache
    file, not a result) and print clang's complaints."""
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.01", "release.settle_time_s=0.01"]))


def limited_cli(*args, cwd, max_file_bytes):
    """``warpcloth ARGS`` in a child whose files may not grow past ``max_file_bytes``
    (writes beyond fail with EFBIG: Python ignores SIGXFSZ)."""
    kernels_compiled()

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_file_bytes, max_file_bytes))

    return subprocess.run(
        [sys.executable, "-m", "warpcloth.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
        preexec_fn=limit,
    )


@pytest.mark.slow
def test_a_disk_that_fills_during_a_run_is_exit_5_and_leaves_the_committed_part(tmp_path):
    # 30 s of the swing: 0.7 MB of frames (reserved at the start) and ~7 MB of probe rows
    # in chunks of growing size; a 3 MB limit stops it while it streams probes.
    done = limited_cli(
        "run",
        "damped_swing",
        "--set",
        "run.duration_s=30",
        "--out",
        "r",
        "--no-progress",
        cwd=tmp_path,
        max_file_bytes=3_000_000,
    )
    assert done.returncode == 5, done.stderr
    assert "I/O error: File too large" in done.stderr and "what was committed before is kept" in done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    meta = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert meta["complete"] is False and meta["committed"]["probe_rows"] > 0
    recording = load_recording(tmp_path / "r")
    assert not recording.complete
    assert len(recording.probes) == meta["committed"]["probe_rows"]
    assert np.isfinite(recording.probes.to_numpy()).all()  # no number read from a torn tail
    assert len(recording.frame_times) == meta["committed"]["frames"] > 0
    assert np.isfinite(recording.frames).all()


def test_a_disk_too_small_for_the_frames_fails_before_any_kernel_runs(tmp_path):
    done = limited_cli("run", "damped_swing", "--out", "r", "--no-progress", cwd=tmp_path, max_file_bytes=50_000)
    assert done.returncode == 5 and "File too large" in done.stderr and "frames.npy" in done.stderr, done.stderr
    meta = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert meta["complete"] is False and meta["committed"]["probe_rows"] == 0


def test_a_full_disk_never_destroys_the_result_being_replaced(tmp_path):
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.2", "release.settle_time_s=0.1"]), out=tmp_path / "r")
    before = {p.name: p.read_bytes() for p in (tmp_path / "r").iterdir()}
    done = limited_cli(
        "run", "damped_swing", "--out", "r", "--overwrite", "--no-progress", cwd=tmp_path, max_file_bytes=300_000
    )
    assert done.returncode == 5, done.stderr
    assert {p.name: p.read_bytes() for p in (tmp_path / "r").iterdir()} == before
    assert load_recording(tmp_path / "r").complete


@pytest.mark.parametrize("stage", ["material", "stage"])
def test_a_full_disk_never_truncates_an_existing_file(tmp_path, stage):
    # material fit-kes and export-usd replace their output only once the new one is whole.
    if stage == "material":
        target = tmp_path / "m.toml"
        args = (
            "material",
            "fit-kes",
            "--tensile",
            "kes_fb1_example",
            "--bending",
            "kes_fb2_example",
            "--density-g-per-cm2",
            "0.02",
            "-o",
            str(target),
            "--overwrite",
        )
        target.write_text("# an existing material file\n" + "x = 1\n" * 10)
        limit = 200
    else:
        wc.simulate(
            wc.load_scene("damped_swing", ["run.duration_s=0.2", "release.settle_time_s=0.1"]), out=tmp_path / "r"
        )
        target = tmp_path / "s.usda"
        target.write_text("#usda 1.0\n")
        args = ("export-usd", str(tmp_path / "r"), "-o", str(target), "--overwrite")
        limit = 2_000
    before = target.read_bytes()
    done = limited_cli(*args, cwd=tmp_path, max_file_bytes=limit)
    assert done.returncode == 5 and "Traceback" not in done.stderr, done.stderr
    assert target.read_bytes() == before


def test_a_run_killed_while_streaming_reads_back_its_committed_part(tmp_path):
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
    )

    def committed(key):
        try:
            return json.loads((out / "meta.json").read_text())["committed"][key]
        except (OSError, ValueError, KeyError):
            return 0

    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and committed("frames") < 20:  # some chunks are committed, more stream
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)  # no handler, no cleanup: wherever it was
    proc.communicate(timeout=60)
    meta = json.loads((out / "meta.json").read_text())
    recording = load_recording(out)
    assert not recording.complete and len(recording.probes) == meta["committed"]["probe_rows"] > 0
    assert np.isfinite(recording.probes.to_numpy()).all()
    assert len(recording.frame_times) == meta["committed"]["frames"] and np.isfinite(recording.frames).all()


# 2e9 probe samples: 0.2 TB in memory, 0.7 on disk (its 2e9 steps asked for, to reach the sizes)
ABSURD = ["run.duration_s=20000", "output.probes_per_frame=1666", "integrator.max_steps=2147483647"]


def test_work_too_large_for_memory_is_refused_with_its_numbers_and_knobs(tmp_path):
    with pytest.raises(
        wc.ResourceError,
        match=r"would take [0-9.]+ [GT]B of memory, more than 50% of the .* "
        r"available; record less \(output.probes_per_frame, output.frame_rate_hz, run.duration_s\)",
    ):
        wc.simulate(wc.load_scene("damped_swing", ABSURD))
    from warpcloth.core.resources import check_memory

    check_memory(10_000, "x", "y", available=21_000)
    with pytest.raises(wc.ResourceError, match="x would take 11 kB of memory, more than 50% of the 20 kB available; y"):
        check_memory(11_000, "x", "y", available=20_000)


def test_work_too_large_for_memory_is_refused_by_the_command_too(tmp_path):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "warpcloth.cli",
            "run",
            "damped_swing",
            "--out",
            "big",
            *(a for s in ABSURD for a in ("--set", s)),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    assert done.returncode == 2 and "warpcloth run: too large: the recorded probes and frames" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "big").exists()


def test_output_too_large_for_the_disk_is_refused_before_anything_is_written(tmp_path):
    # 2e6 frames of 1666 probe samples: ~1 TB of probes.csv, refused by its estimate
    # before the run directory exists.
    from warpcloth.io.run_dir import RunWriter

    scene = wc.load_scene("damped_swing", ["output.probes_per_frame=1666"])
    with pytest.raises(
        wc.ResourceError,
        match=r"the run's frames.npy and probes.csv would write [0-9.]+ TB to "
        r".*big, whose file system has [0-9.]+ [kMGT]?B free; free space, choose another --out",
    ):
        RunWriter(tmp_path / "big", [scene], scene.n_nodes, np.zeros(2_000_000))
    assert not (tmp_path / "big").exists()
    from warpcloth.core.resources import check_disk

    check_disk(tmp_path / "new" / "deeper", 1, "x", "y")  # a path that does not exist yet is measured by its parent


def test_a_huge_sweep_is_refused_before_it_is_expanded(tmp_path):
    started = time.monotonic()
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "warpcloth.cli",
            "sweep",
            "damped_swing_sweep",
            "--set",
            "sweep.random.samples=1000000",
            "--out",
            "s",
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    assert done.returncode == 2 and "the sweep has 1000000 variants, more than 100000" in done.stderr
    assert "--max-variants" in done.stderr and not (tmp_path / "s").exists()
    assert time.monotonic() - started < 60  # not minutes of expansion first
    with pytest.raises(wc.ArgumentError, match="^max_variants: the sweep has 12 variants, more than 10"):
        wc.load_sweep("damped_swing_sweep", ["sweep.random.samples=12"], max_variants=10)


def test_two_runs_started_into_one_directory_never_interleave(tmp_path):
    # Started together, both may find --out empty; exactly one writes it, the other is
    # refused, and what is left is one complete run equal to a run made alone.
    args = [
        sys.executable,
        "-m",
        "warpcloth.cli",
        "run",
        "damped_swing",
        "--set",
        "run.duration_s=1",
        "--no-progress",
        "--out",
        "r",
    ]
    procs = [
        subprocess.Popen(args, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    outcomes = sorted((p.wait(timeout=300), p.communicate()[1]) for p in procs)
    assert outcomes[0][0] == 0 and outcomes[1][0] == 2, outcomes
    assert "is being written by another warpcloth process" in outcomes[1][1] or "already holds" in outcomes[1][1], (
        outcomes[1][1]
    )
    recording = load_recording(tmp_path / "r")
    alone = wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=1"]))
    assert recording.complete and len(recording.probes) == len(alone.t)
    np.testing.assert_array_equal(recording.probes["tip_x"].to_numpy(), alone.probe("tip_x", 0))


@pytest.mark.slow
def test_an_overwrite_never_pulls_a_directory_from_under_a_running_writer(tmp_path):
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
        preexec_fn=interruptible,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (out / ".writing").is_file():
        time.sleep(0.05)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "warpcloth.cli",
            "run",
            "damped_swing",
            "--set",
            "run.duration_s=0.1",
            "--no-progress",
            "--out",
            str(out),
            "--overwrite",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=60)
    assert done.returncode == 2 and f"is being written by another warpcloth process (pid {proc.pid})" in done.stderr
    assert json.loads((out / "meta.json").read_text())["n_variants"] == 1 and not load_recording(out).complete


@pytest.mark.parametrize(
    "damage",
    [
        "a digit changed to a letter",
        "frames.npy truncated",
        "rows miscounted",
        "complete is a string",
        "frames of another shape",
        "a row of a variant the run lacks",
        "the run's scene copy changed",
    ],
)
def test_a_damaged_complete_run_is_refused_by_name(tmp_path, damage):
    out = tmp_path / "r"
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.1", "release.settle_time_s=0.1"]), out=out)
    meta = json.loads((out / "meta.json").read_text())
    if damage == "a digit changed to a letter":
        text = (out / "probes.csv").read_text().splitlines()
        text[5] = "X" + text[5][1:]
        (out / "probes.csv").write_text("\n".join(text) + "\n")
        expected = r"probes.csv, line 6: t is 'X.*', not a number"
    elif damage == "frames.npy truncated":
        data = (out / "frames.npy").read_bytes()
        (out / "frames.npy").write_bytes(data[:1000])
        expected = "frames.npy: cannot be read as the run's frames"
    elif damage == "rows miscounted":
        meta["committed"]["probe_rows"] += 5
        expected = "probes.csv: holds 61 rows but meta.json records 66"
    elif damage == "a row of a variant the run lacks":
        text = (out / "probes.csv").read_text().splitlines()
        cells = text[5].split(",")
        text[5] = ",".join([cells[0], "4", *cells[2:]])
        (out / "probes.csv").write_text("\n".join(text) + "\n")
        expected = "probes.csv, line 6: variant is 4, but the run has 1"
    elif damage == "the run's scene copy changed":
        scene = (out / "scene.toml").read_text()
        (out / "scene.toml").write_text(scene.replace("free_length_mm = ", "free_length_mm = -", 1))
        expected = "scene.toml: is the run's copy of its scene and this warpcloth refuses it"
    elif damage == "complete is a string":
        meta["complete"] = "yes"
        expected = "meta.json: complete must be true or false"
    else:
        meta["n_nodes"] = 99
        expected = r"frames.npy: holds frames of shape \(7, 1, 25, 2\), but the run recorded \(7, 1, 99, 2\)"
    (out / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(wc.DataFileError, match=expected):
        load_recording(out)


@pytest.mark.parametrize(
    "args, message",
    [
        (("run", "./damped_swing"), "damped_swing: no such scene file (a path, because it has a directory part"),
        (
            ("run", "damped_swing", "--set", "strip.spacing_mm=1e-7"),
            "1e-05 s is above the semi_implicit scheme's stability limit 1.017e-12 s",
        ),
        (
            ("run", "damped_swing", "--set", "strip.spacing_mm=1e-7", "--set", 'integrator.scheme="imex"'),
            "too large: the state of 1 strip(s) of",
        ),
        (
            ("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--bounds", "gamma=-5:1"),
            "--bounds: gamma = -5 is not a valid scene: damping.gamma_per_s: must be ≥ 0",
        ),
        (
            (
                "fit",
                "damped_swing",
                "--measured",
                "damped_swing_laser",
                "--free",
                "gamma",
                "--set",
                "damping.gamma_per_s=-1",
            ),
            "damping.gamma_per_s: must be ≥ 0, got -1 (set by the override damping.gamma_per_s=-1)",
        ),
        (("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma,gamma"), "is named twice"),
        (
            ("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--align-start", "1e9"),
            "--align-start: 1e+09 s is longer than the measured record",
        ),
        (
            (
                "fit",
                "damped_swing",
                "--measured",
                "damped_swing_laser",
                "--free",
                "gamma",
                "--space-filling",
                "100000000",
            ),
            "--space-filling: 100000000 variants in one launch is more than 10000",
        ),
        (("sweep", "damped_swing_sweep", "--workers", "100000"), "--workers: 100000 threads on"),
        (("sweep", "damped_swing_sweep", "--scheduler", "notanaddress"), "--scheduler: 'notanaddress' is not a"),
    ],
)
def test_inputs_that_once_crashed_hung_or_misled_are_named(tmp_path, args, message):
    done = subprocess.run(
        [sys.executable, "-m", "warpcloth.cli", *args, "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "o").exists()


def test_overwrite_replaces_a_run_never_other_files(tmp_path):
    keep = tmp_path / "notes"
    keep.mkdir()
    (keep / "thesis.tex").write_text("months of work")
    done = subprocess.run(
        [sys.executable, "-m", "warpcloth.cli", "run", "damped_swing", "--out", str(keep), "--overwrite"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and "--overwrite replaces only a run directory, never other files" in done.stderr
    assert (keep / "thesis.tex").read_text() == "months of work"


@pytest.mark.slow
def test_ctrl_c_stops_a_threaded_sweep_promptly_and_it_resumes(tmp_path):
    # Batches on two threads: Ctrl-C drops the batches not started (the running ones
    # finish their files), exits 130 within a batch's time, and a rerun completes the rest.
    args = [
        sys.executable,
        "-m",
        "warpcloth.cli",
        "sweep",
        "damped_swing_sweep",
        "--set",
        "sweep.random.samples=40",
        "--set",
        "run.duration_s=3",
        "--max-batch",
        "4",
        "--workers",
        "2",
        "--no-progress",
        "--out",
        "s",
    ]
    proc = subprocess.Popen(
        args, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=interruptible
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list((tmp_path / "s" / "summary").glob("*.parquet"))) < 2:
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    signalled = time.monotonic()
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "interrupted" in stderr and "Traceback" not in stderr, stderr
    assert time.monotonic() - signalled < 20  # not the rest of the sweep first
    assert len(list((tmp_path / "s" / "summary").glob("*.parquet"))) < 10  # of 10 batches
    done = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "40 variants" in done.stdout, done.stderr


def test_figures_are_results_too(tmp_path):
    # plot and render into a directory that holds figures, and --plot onto an existing
    # file, are refused without --overwrite; figures are written atomically.
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.2", "release.settle_time_s=0.1"]), out=tmp_path / "r")

    def cli(*args):
        return run_cli(*args, cwd=tmp_path)

    assert cli("plot", "r").returncode == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "r" / "figures").iterdir()}
    again = cli("plot", "r")
    assert again.returncode == 2 and "--out" in again.stderr and "--overwrite" in again.stderr
    assert {p.name: p.read_bytes() for p in (tmp_path / "r" / "figures").iterdir()} == before
    assert cli("plot", "r", "--overwrite").returncode == 0
    (tmp_path / "c.png").write_bytes(b"an existing figure")
    done = cli(
        "clamp",
        "fit-angle",
        "impulsive_rotation_encoder",
        "--scene",
        "impulsive_rotation",
        "-o",
        "m.toml",
        "--plot",
        "c.png",
    )
    assert done.returncode == 2 and (tmp_path / "c.png").read_bytes() == b"an existing figure"
    done = cli(
        "clamp",
        "fit-angle",
        "impulsive_rotation_encoder",
        "--scene",
        "impulsive_rotation",
        "-o",
        "m.toml",
        "--plot",
        "figure",
    )
    assert done.returncode == 2 and "--plot: figure must be a file ending in .png" in done.stderr
    assert not list(tmp_path.rglob(".*.tmp*"))


def cli(*args, cwd, timeout=300):
    """``warpcloth ARGS`` in a child process, run to its end."""
    return subprocess.run(
        [sys.executable, "-m", "warpcloth.cli", *args], capture_output=True, text=True, cwd=cwd, timeout=timeout
    )


def one_line_error(done, status):
    """The child exited ``status`` with exactly one line on stderr and no traceback."""
    assert done.returncode == status and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr


@pytest.mark.parametrize(
    "command, delay_s",
    [
        (("run", "damped_swing", "--set", "run.duration_s=600", "--out", "r"), 0.1),  # importing the modules
        (("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--out", "f"), 0.7),
    ],
)
def test_ctrl_c_while_starting_is_exit_130_and_one_line(tmp_path, command, delay_s):
    # Whether it lands in the imports, Warp's start or the first step of the work, an early
    # Ctrl-C is exit 130 with one line, never a KeyboardInterrupt traceback. The delay counts
    # from the moment the interpreter runs the program's entry: one that lands in CPython's
    # own start (site's .pth files, under load) is CPython's fatal error, before warpcloth.
    entry = "import sys\nprint('entered', file=sys.stderr, flush=True)\nfrom warpcloth.cli import program\nprogram()"
    proc = subprocess.Popen(
        [sys.executable, "-c", entry, *command, "--no-progress"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )
    assert proc.stderr.readline().strip() == "entered"
    time.sleep(delay_s)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in stderr and "interrupted" in stderr, stderr
    assert len(stderr.strip().splitlines()) == 1, stderr


def test_ctrl_c_inside_a_class_being_defined_at_start_is_exit_130(monkeypatch, capsys):
    # Python 3.11 wraps a KeyboardInterrupt raised in a dataclass field's __set_name__ (while
    # a module's class body runs) in a RuntimeError; CI's start-up test landed there once
    import types

    from warpcloth import cli

    class Starting(types.ModuleType):
        def __getattr__(self, name):
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as exc:
                raise RuntimeError("Error calling __set_name__ on 'Field' instance") from exc

    monkeypatch.setitem(sys.modules, "warpcloth.cli.app", Starting("warpcloth.cli.app"))
    assert cli.main(["run", "damped_swing"]) == 130
    assert "interrupted" in capsys.readouterr().err

    class Broken(types.ModuleType):
        def __getattr__(self, name):
            raise RuntimeError("a real bug")

    monkeypatch.setitem(sys.modules, "warpcloth.cli.app", Broken("warpcloth.cli.app"))
    with pytest.raises(RuntimeError, match="a real bug"):  # anything else is not an interrupt
        cli.main(["run", "damped_swing"])


def holding(marker):
    """A child process that holds ``marker`` as a writer does (until killed)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time\nfrom warpcloth.io.writing import hold\n"
            f"assert hold({str(marker)!r}) is None\nprint('held', flush=True)\ntime.sleep(300)",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline().strip() == "held"
    return proc


@pytest.mark.parametrize(
    "args, result",
    [
        (("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--out", "f"), "f"),
        (
            ("clamp", "fit-angle", "impulsive_rotation_encoder", "--scene", "impulsive_rotation", "-o", "c.toml"),
            "c.toml",
        ),
        (
            (
                "material",
                "fit-kes",
                "--tensile",
                "kes_fb1_example",
                "--bending",
                "kes_fb2_example",
                "--density-g-per-cm2",
                "0.02",
                "-o",
                "m.toml",
            ),
            "m.toml",
        ),
        (("export-usd", "r", "-o", "s.usda"), "s.usda"),
        (("plot", "r", "--out", "figs"), "figs"),
    ],
)
def test_a_result_another_process_is_writing_is_refused_by_every_command(tmp_path, args, result):
    if "r" in args:
        wc.simulate(
            wc.load_scene("damped_swing", ["run.duration_s=0.1", "release.settle_time_s=0.1"]), out=tmp_path / "r"
        )
    from warpcloth.io.writing import marker_of

    writer = holding(marker_of(tmp_path / result))
    try:
        done = cli(*args, cwd=tmp_path)
    finally:
        writer.kill()
        writer.wait()
    one_line_error(done, 2)
    assert f"{result} is being written by another warpcloth process (pid {writer.pid})" in done.stderr
    assert not (tmp_path / result).exists()
    # the marker a killed writer leaves holds nothing: the same command now writes its result
    assert marker_of(tmp_path / result).exists()
    if args[0] == "material":
        assert cli(*args, cwd=tmp_path).returncode == 0 and (tmp_path / result).is_file()


def test_two_material_fits_into_one_new_file_never_replace_each_other(tmp_path):
    args = [
        sys.executable,
        "-m",
        "warpcloth.cli",
        "material",
        "fit-kes",
        "--tensile",
        "kes_fb1_example",
        "--bending",
        "kes_fb2_example",
        "--density-g-per-cm2",
        "0.02",
        "-o",
        "m.toml",
    ]
    procs = [
        subprocess.Popen(
            [*args, "--name", name], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for name in ("first", "second")
    ]
    outcomes = [(p.wait(timeout=300), p.communicate()[1]) for p in procs]
    assert sorted(code for code, _ in outcomes) == [0, 2], outcomes
    refused = next(err for code, err in outcomes if code == 2)
    assert "is being written by another warpcloth process" in refused or "already exists" in refused, refused
    winner = ("first", "second")[[code for code, _ in outcomes].index(0)]
    assert f'name = "{winner}"' in (tmp_path / "m.toml").read_text()


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ("sweep", "damped_swing_sweep", "--set", "sweep.random.samples=30000000", "--max-variants", "100000000000"),
            "too large: the sweep's 30000000 variant scenes would take 600 GB of memory",
        ),
        (("sweep", "damped_swing_sweep", "--set", "sweep.random.samples=2e10"), "the sweep has 20000000000 variants"),
        (("run", "damped_swing", "--set", "strip.clamp_length_mm=1e300"), "are 2e+299 nodes, more than 2147483647"),
        (
            ("run", "damped_swing", "--set", "strip.spacing_mm=1e-6", "--set", "strip.free_length_mm=1e5"),
            "are 1e+11 nodes, more than 2147483647",
        ),
        (
            ("fit", "damped_swing", "--measured", "damped_swing_laser", "--free", "gamma", "--bootstrap", str(10**15)),
            f"too large: --bootstrap {10**15}: the resamples would take",
        ),
    ],
)
def test_sizes_are_checked_in_closed_form_before_anything_is_allocated(tmp_path, args, message):
    started = time.monotonic()
    done = cli(*args, "--out", "o", cwd=tmp_path)
    one_line_error(done, 2)
    assert message in done.stderr and not (tmp_path / "o").exists()
    assert time.monotonic() - started < 60  # refused at once, not after a sampler or a fit


def test_a_size_beyond_a_float_is_written_without_overflowing():
    from warpcloth.core.resources import check_memory, size_text

    assert size_text(10**400) == "1.00e+388 TB" and size_text(3 * 10**12) == "3 TB"
    with pytest.raises(wc.ResourceError, match=r"x would take 1.00e\+388 TB of memory"):
        check_memory(10**400, "x", "y")


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, message",
    [
        # 3000 variants × 0.6 GB of probes and frames: ~2 TB, though one batch of one fits memory and disk
        (
            (
                "--set",
                "run.duration_s=20000",
                "--set",
                "integrator.max_steps=2147483647",
                "--set",
                "output.probes_per_frame=1",
                "--set",
                "sweep.random.samples=3000",
                "--frames",
                "--workers",
                "1",
                "--max-batch",
                "1",
            ),
            r"too large: the probes and frames of the sweep's 3000 remaining variants would write [0-9.]+ TB to .*s, "
            r"whose file system has",
        ),
        # four strips of ~450 GB of results each
        (
            (
                "--set",
                "run.duration_s=20000",
                "--set",
                "integrator.max_steps=2147483647",
                "--set",
                "output.probes_per_frame=1666",
                "--set",
                "sweep.random.samples=4",
                "--workers",
                "2",
            ),
            r"too large: the recorded probes of 2 sweep batch\(es\) running side by side would take 896 GB of memory",
        ),
    ],
)
def test_a_sweep_is_sized_as_a_whole_before_its_first_batch(tmp_path, args, message):
    done = cli("sweep", "damped_swing_sweep", *args, "--no-progress", "--out", "s", cwd=tmp_path)
    one_line_error(done, 2)
    assert re.search(message, done.stderr), done.stderr
    assert not (tmp_path / "s").exists()  # nothing laid out, nothing simulated


def test_probe_rows_out_of_time_order_are_refused_by_name(tmp_path):
    # Same rows, same bytes, reordered: a period read from them would be wrong.
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.3", "release.settle_time_s=0.1"]), out=tmp_path / "r")
    lines = (tmp_path / "r" / "probes.csv").read_text().splitlines()
    lines[7:10] = [lines[8], lines[9], lines[7]]  # three rows rotated
    (tmp_path / "r" / "probes.csv").write_text("\n".join(lines) + "\n")
    done = cli("analyse", "r", cwd=tmp_path)
    one_line_error(done, 2)
    assert (
        "probes.csv, line 10: t = 0.01 s of variant 0 comes after t = 0.01333 s (line 9): the rows are out of "
        "time order" in done.stderr
    )


def test_frame_times_out_of_order_are_refused(tmp_path):
    out = tmp_path / "r"
    wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.2", "release.settle_time_s=0.1"]), out=out)
    times = np.load(out / "frame_times.npy")
    times[[2, 3]] = times[[3, 2]]
    np.save(out / "frame_times.npy", times)
    with pytest.raises(
        wc.DataFileError,
        match=r"frame_times.npy: frame 3 at t = 0.03333 s does not come after "
        r"frame 2 at 0.05 s",
    ):
        load_recording(out)


def test_sweep_probes_out_of_time_order_are_refused(tmp_path):
    import pandas as pd

    done = cli(
        "sweep",
        "damped_swing_sweep",
        "--set",
        "sweep.random.samples=2",
        "--set",
        "run.duration_s=0.2",
        "--frames",
        "--probes",
        "all",
        "--no-progress",
        "--out",
        "s",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    batch = sorted((tmp_path / "s" / "probes").glob("*.parquet"))[0]
    table = pd.read_parquet(batch)
    table.iloc[[4, 5]] = table.iloc[[5, 4]].to_numpy()
    table.to_parquet(batch, index=False)
    with pytest.raises(wc.DataFileError, match=rf"{batch.name}: t = .* s of variant 0 comes after .* \(row 5\)"):
        load_recording(tmp_path / "s")


@pytest.mark.parametrize(
    "header, rows, message",
    [
        ("t_s,x [yd]", "0,1\n0.1,2\n", "column 2 is headed 'x [yd]': 'yd' is not a length unit"),
        (
            "t_s,displacement_thou",
            "0,1\n0.1,2\n",
            "column 2 is headed 'displacement_thou': 'thou' is not a length unit",
        ),
        ("t (fortnight),x_mm", "0,1\n0.1,2\n", "column 1 is headed 't (fortnight)': 'fortnight' is not a time unit"),
        ("t_s,theta_grads", "0,0\n0.1,2\n", "column 2 is headed 'theta_grads': 'grads' is not an angle unit"),
        (
            "frame,t_s,s_parsec,x_mm,y_mm",
            "0,0,10,1,2\n1,0.1,10,1,2\n",
            "column 3 is headed 's_parsec': 'parsec' is not a length unit",
        ),
    ],
)
def test_a_unit_the_header_states_is_refused_unless_known(tmp_path, header, rows, message):
    (tmp_path / "m.csv").write_text(f"{header}\n{rows}")
    done = (
        cli("analyse", "m.csv", cwd=tmp_path)
        if "theta" not in header
        else cli("clamp", "fit-angle", "m.csv", "--scene", "impulsive_rotation", "-o", "c.toml", cwd=tmp_path)
    )
    one_line_error(done, 2)
    assert f"m.csv, line 1: {message}" in done.stderr and not (tmp_path / "c.toml").exists()


@pytest.fixture(scope="module")
def short_result():
    return wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.05", "release.settle_time_s=0.1"]))


@pytest.mark.parametrize(
    "keywords, error, message",
    [
        (
            {"initial_positions": np.zeros((24, 1, 2))},
            wc.ArgumentError,
            r"initial_positions: has shape \(24, 1, 2\); expected \(25, 1, 2\)",
        ),
        (
            {"initial_positions": np.full((25, 1, 2), np.inf)},
            wc.ArgumentError,
            r"initial_positions: \[0, 0, 0\] is inf; every value must be finite",
        ),
        ({"initial_positions": [["a"]]}, wc.ArgumentTypeError, r"initial_positions: must be an array of numbers"),
        (
            {"initial_velocities": np.zeros((25, 1, 2))},
            wc.ArgumentError,
            "initial_velocities: given without initial_positions",
        ),
    ],
)
def test_simulate_names_a_wrong_start_instead_of_diverging(keywords, error, message):
    with pytest.raises(error, match=message):
        wc.simulate(wc.load_scene("damped_swing", ["run.duration_s=0.05"]), **keywords)


@pytest.mark.parametrize(
    "call, error, message",
    [
        (
            lambda r: r.probe("tip_x", variant=-2),
            wc.ArgumentError,
            r"variant: -2 is not one of the 1 variants \(0 to 0\)",
        ),
        (lambda r: r.probe("tip_x", variant=1), wc.ArgumentError, "variant: 1 is not one of the 1 variants"),
        (lambda r: r.probe("tip_x", variant=0.0), wc.ArgumentTypeError, "variant: must be an integer index"),
        (lambda r: r.probe("tip_z"), wc.ArgumentError, "name: 'tip_z' is not a probe; the probes are tip_x, tip_y"),
    ],
)
def test_a_result_refuses_an_index_or_name_it_does_not_have(short_result, call, error, message):
    with pytest.raises(error, match=message):
        call(short_result)


@pytest.mark.parametrize(
    "n_strips, n_variants, message",
    [
        (1, 2, "meta.json: n_variants is 2, but the run directory holds one scene.toml"),
        (2, 1, r"meta.json: n_variants is 1, but the run directory holds 2 variant scene\(s\) in variants/"),
        (2, 3, r"meta.json: n_variants is 3, but the run directory holds 2 variant scene\(s\) in variants/"),
    ],
)
def test_a_damaged_run_directory_names_the_file_that_is_wrong(tmp_path, n_strips, n_variants, message):
    out = tmp_path / "r"
    wc.simulate(
        [wc.load_scene("damped_swing", ["run.duration_s=0.05", "release.settle_time_s=0.1"])] * n_strips, out=out
    )
    with pytest.raises(wc.ArgumentError, match="^variants: .*a range is START:STOP"):
        load_recording(out, variants="-1:")
    meta = json.loads((out / "meta.json").read_text())
    (out / "meta.json").write_text(json.dumps(meta | {"n_variants": n_variants}))
    with pytest.raises(wc.DataFileError, match=message):
        load_recording(out)
    with pytest.raises(TypeError, match="load_recording takes the path"):
        load_recording(None)


def fb1_without_unit(tmp_path):
    """The example KES-FB1 loop (strain in percent) with a header that does not say so."""
    from warpcloth.io.measured import bundled_data

    rows = bundled_data("kes_fb1_example").read_text().splitlines()[1:]
    (tmp_path / "fb1.csv").write_text("\n".join(["strain,force_gf_per_cm", *rows]) + "\n")
    return "fb1.csv"


@pytest.mark.parametrize(
    "case, warning",
    [
        ("density 0.5", "--density-g-per-cm2: areal density 0.5 g/cm² is outside the plausible 0.001 to 0.2 g/cm²"),
        ("density 1e-5", "--density-g-per-cm2: areal density 1e-05 g/cm² is outside the plausible 0.001 to 0.2 g/cm²"),
        (
            "percent read as fraction",
            "fb1.csv, column 1 read as fraction: largest tensile strain 6.001 (fraction) is "
            "outside the plausible 0.001 to 1 (fraction)",
        ),
    ],
)
def test_an_implausible_kes_input_is_named_with_its_range(tmp_path, case, warning):
    density = case.split()[1] if case.startswith("density") else "0.02"
    extra = ("--strain-unit", "fraction") if "fraction" in case else ()
    done = cli(
        "material",
        "fit-kes",
        "--tensile",
        fb1_without_unit(tmp_path),
        "--bending",
        "kes_fb2_example",
        "--density-g-per-cm2",
        density,
        *extra,
        "-o",
        "m.toml",
        "--accept",
        cwd=tmp_path,
    )
    assert done.returncode == 0 and f"warpcloth material: warning: {warning}" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and done.stderr.count("warning:") == 1


@pytest.mark.parametrize(
    "text, warning",
    [
        (
            "t,x\n" + "".join(f"{i * 10},{0.02 * np.sin(i / 3):.5f}\n" for i in range(400)),  # ms and metres
            [
                "column 1 (headed 't', no unit): record length 3990 s is outside the plausible 0.01 to 3600 s",
                "column 1 (headed 't', no unit): sampling interval 10 s is outside the plausible 1e-07 to 0.1 s",
                "column 2 (headed 'x', no unit): largest displacement 0.02 mm is outside the plausible 0.1 to 2000 mm",
            ],
        ),
        (
            "".join(f"{i / 100},{30 * np.sin(i / 9):.4f}\n" for i in range(300)),  # millimetres, no header: fine
            [],
        ),
        (
            # ms over a record short enough to pass as seconds: named by its sampling interval alone
            "t,x\n" + "".join(f"{i},{30 * np.sin(i / 9):.4f}\n" for i in range(300)),
            ["column 1 (headed 't', no unit): sampling interval 1 s is outside the plausible 1e-07 to 0.1 s"],
        ),
    ],
)
def test_a_trace_that_looks_like_another_unit_is_named(tmp_path, text, warning):
    (tmp_path / "trace.csv").write_text(text)
    done = cli("analyse", "trace.csv", cwd=tmp_path)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.count("warning:") == len(warning) and all(w in done.stderr for w in warning), done.stderr


@pytest.mark.parametrize(
    "overrides, message",
    [
        (
            ("output.laser_height_mm=-150",),
            "output.laser_height_mm: -150 mm is not on the hanging strip, which reaches from 0 to -100 mm",
        ),
        (("output.laser_height_mm=5",), "output.laser_height_mm: 5 mm is not on the hanging strip"),
        (
            ("strip.free_length_mm=60", "release.hold_x_mm=30", "release.hold_y_mm=-40"),
            "output.laser_height_mm: -80 mm is not on the hanging strip, which reaches from 0 to -60 mm",
        ),
    ],
)
def test_a_laser_line_off_the_strip_is_refused_before_the_run(tmp_path, overrides, message):
    done = cli("run", "damped_swing", *(a for o in overrides for a in ("--set", o)), "--out", "r", cwd=tmp_path)
    one_line_error(done, 2)
    assert message in done.stderr and not (tmp_path / "r").exists()


def test_a_density_out_of_range_in_a_scene_is_warned_about(tmp_path):
    done = cli(
        "run",
        "damped_swing",
        "--set",
        "material.density_g_per_cm2=3",
        "--set",
        "run.duration_s=0.05",
        "--no-progress",
        "--out",
        "r",
        cwd=tmp_path,
    )
    assert done.returncode == 0 and done.stderr.count("warning:") == 1, done.stderr
    assert (
        "material.density_g_per_cm2: areal density 3 g/cm² is outside the plausible 0.001 to 0.2 g/cm²" in done.stderr
    )


def scaled_copy(bundled, scale, path):
    """A bundled two-column example written to ``path`` with its second column × ``scale``."""
    from warpcloth.io.measured import bundled_data

    rows = bundled_data(bundled).read_text().splitlines()
    scaled = [f"{r.split(',')[0]},{float(r.split(',')[1]) * scale:.6g}" for r in rows[1:]]
    path.write_text("\n".join([rows[0], *scaled]) + "\n")


@pytest.mark.parametrize("scale", ["1e300", "-1e300"])
def test_a_kes_fit_that_overflows_writes_no_material_file(tmp_path, scale):
    scaled_copy("kes_fb1_example", float(scale), tmp_path / "fb1.csv")
    done = cli(
        "material",
        "fit-kes",
        "--tensile",
        "fb1.csv",
        "--bending",
        "kes_fb2_example",
        "--density-g-per-cm2",
        "0.02",
        "-o",
        "m.toml",
        "--accept",
        cwd=tmp_path,
    )
    one_line_error(done, 2)
    assert (
        "fb1.csv: the fit gave the tensile RMS = inf, not a finite number: no material file is written"
        if scale == "1e300"
        else "fb1.csv: no quartic T(ε) rising on [0, 0.25] fits this loop"
    ) in done.stderr
    assert not (tmp_path / "m.toml").exists()


@pytest.mark.slow
def test_a_kes_shear_fit_that_overflows_writes_no_material_file(tmp_path):
    # issue 39: a shear loop scaled by 1e300 was "failed", yet written with
    # hysteresis_d1_gf_per_cm ≈ 1e302; tensile and bending fits already refused this
    scaled_copy("kes_fb1_shear_example", 1e300, tmp_path / "fb1s.csv")
    done = cli(
        "material",
        "fit-kes",
        "--tensile",
        "kes_fb1_example",
        "--bending",
        "kes_fb2_example",
        "--shear",
        "fb1s.csv",
        "--density-g-per-cm2",
        "0.02",
        "-o",
        "m.toml",
        "--accept",
        cwd=tmp_path,
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "fb1s.csv, column 2: largest shear force 5.2e+300 gf/cm is outside the plausible" in done.stderr
    assert "fb1s.csv: the shear fit gave shear_rms_gf_per_cm = inf, not a finite number" in done.stderr
    assert not (tmp_path / "m.toml").exists()


@pytest.mark.parametrize(
    "args, words",
    [
        # issue 39: the sheet's auto step collapsed to 1.06e-10 s and ran for minutes without a word
        (
            ("run", "shear_swing", "--set", "shear.rigidity_gf_per_cm_deg=1e12"),
            (
                '1.2 s of settling and record at dt = 1.063e-10 s (chosen by dt_s = "auto"',
                "1.13e+10 steps of each sheet",
                "days",
            ),
        ),
        (
            ("run", "damped_swing", "--set", "integrator.dt_s=1e-8"),
            (
                "integrator.dt_s: 4.3 s of settling and record at dt = 1e-08 s",
                "4.3e+08 steps of each strip",
                "max_steps = 100000000",
            ),
        ),
        (
            ("sweep", "damped_swing_sweep", "--set", "integrator.dt_s=1e-8"),
            ("integrator.dt_s: 3.3 s of settling and record at dt = 1e-08 s", "raise integrator.max_steps"),
        ),
        (
            ("run", "damped_swing", "--set", "integrator.max_steps=3000000000"),
            ("integrator.max_steps: 3000000000 is more than a kernel counts (2147483647)",),
        ),
    ],
)
def test_a_step_count_beyond_reason_is_refused_before_it_starts(tmp_path, args, words):
    done = run_cli(*args, "--no-progress", "--out", tmp_path / "o")
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    for word in words:
        assert word in done.stderr, done.stderr
    assert not (tmp_path / "o").exists()


def test_a_long_run_asked_for_runs_and_says_how_long_first(monkeypatch):
    import warpcloth.core.runner as runner

    # raising integrator.max_steps lets the refused step through (checked, not run: 4.3e8 steps)
    scene = wc.load_scene("damped_swing", ["integrator.dt_s=1e-8", "integrator.max_steps=500000000"])
    assert scene.integrator.max_steps == 500_000_000
    # a run past LONG_RUN_STEPS says its steps and estimated time before the first launch
    monkeypatch.setattr(runner, "LONG_RUN_STEPS", 1000)
    with pytest.warns(
        wc.errors.LongRunWarning, match=r"1\.4e\+05 steps of each of 1 strip\(s\) of 25 nodes .* CPU core"
    ):
        wc.run("damped_swing", ["run.duration_s=0.1"], device="cpu")


def test_messages_name_what_the_user_gave(tmp_path):
    # issue 39: each of these named a hidden temporary file, printed a codec's own line
    # first, or read "pid -1"
    import fcntl
    import os

    from warpcloth.io.writing import claim_result, marker_of

    wc.run("damped_swing", ["run.duration_s=0.05"], out=tmp_path / "r")
    (tmp_path / "s.usda").mkdir()
    done = run_cli("export-usd", tmp_path / "r", "-o", tmp_path / "s.usda", "--overwrite")
    assert done.returncode == 2 and "-o: " in done.stderr and "s.usda is a directory; -o names the file" in done.stderr
    from pathlib import Path

    board = Path(__file__).resolve().parents[1] / "scenes" / "data" / "track" / "board_0.png"
    (tmp_path / "cut.png").write_bytes(board.read_bytes()[:20000])
    done = run_cli(
        "track",
        "calibrate",
        tmp_path / "cut.png",
        board,
        board,
        "--board",
        "11x10",
        "--square-mm",
        "10",
        "--origin-corner",
        "1,1",
        "-o",
        tmp_path / "p.json",
    )
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "cut.png: cannot be read as an image" in lines[0], lines
    # a writer that has taken its marker but not yet written its pid
    marker = marker_of(tmp_path / "busy.csv")
    fd = os.open(marker, os.O_CREAT | os.O_RDWR)
    fcntl.flock(fd, fcntl.LOCK_EX)
    try:
        with pytest.raises(wc.ArgumentError, match="another warpcloth process .one just starting, its pid not yet"):
            claim_result(tmp_path / "busy.csv", "-o")
    finally:
        os.close(fd)
