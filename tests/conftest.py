"""Shared helpers: every test runs on the CPU device (CI has no GPU)."""

import logging
import signal

import warp as wp

wp.config.log_level = logging.WARNING


def kernel_variants() -> dict:
    """Every kernel the project can load, by ``[sheet.]name-precision[-scheme]``: each
    (precision, scheme) of the strip's fused kernel, the hinge, held-end and law-path kernels,
    the sheet's three (tests/test_cuda_build.py compiles them for CUDA)."""
    from warpcloth.kernels import build_strip, drives, hinge_kernels, laws, sheet

    from warpcloth.strip import PRECISIONS, SOLVERS

    def kernels(namespace: object) -> dict:
        return {name: value for name, value in vars(namespace).items() if isinstance(value, wp.Kernel)}

    out = {}
    for precision, scalar in PRECISIONS.items():
        for scheme in SOLVERS:
            for name, kernel in kernels(build_strip(scalar, scheme)).items():
                out[f"{name}-{precision}-{scheme}"] = kernel
        for prefix, namespace in (
            ("", hinge_kernels(scalar)),
            ("", drives.build(scalar)),
            ("", laws.build(scalar)),
            ("sheet.", sheet.build(scalar)),
        ):
            for name, kernel in kernels(namespace).items():
                out[f"{prefix}{name}-{precision}"] = kernel
    return out


def pytest_configure(config) -> None:
    """Fill Warp's kernel cache once, in the process that starts the workers, before any
    test runs: with a cold cache (a fresh clone in CI) every worker and every command a
    test starts in a process of its own would otherwise compile the same kernels at the
    same time (23 s of compiling, done many times over)."""
    if hasattr(config, "workerinput"):  # a pytest-xdist worker: the controller has done it
        return
    from warpcloth.strip.model import init_warp_quietly

    init_warp_quietly()
    from warpcloth.kernels import build_strip
    from warpcloth.kernels.exp_lanes import lane_width

    from warpcloth.strip import SOLVERS

    # and the strip's kernels as this CPU runs them: hinges in groups where it can
    lanes = lane_width(wp.float64, True)
    grouped = [build_strip(wp.float64, scheme, (), lanes).advance for scheme in SOLVERS] if lanes > 1 else []
    for kernel in [*kernel_variants().values(), *grouped]:
        wp.load_module(kernel.module, device="cpu")


LONGEST_FIRST = (
    "test_sheet_fit.py",
    "test_readme.py",
    "test_docs_site.py",
    "test_sheet_plate_scenes.py",
    "test_faults.py",
    "test_fit_set_and_grip.py",
    "test_calibration_path.py",
    "test_fit.py",
    "test_track_rig.py",
    "test_plate_bending.py",
)
"""The modules that take longest on the 2-core sandbox (`pytest --durations`), most first."""


def pytest_collection_modifyitems(session, config, items) -> None:
    """Start the longest modules first. pytest-xdist's ``--dist loadscope`` hands whole
    modules to the workers in collection order, so a long module collected last (they
    are alphabetical) ran alone at the end while the other core idled: longest first
    lets the short ones fill in behind them."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep their order


def overrides(**fields):
    """``section__field=value`` keyword arguments as ``--set`` strings."""
    out = []
    for key, value in fields.items():
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, str):
            text = f'"{value}"'
        else:
            text = repr(value)
        out.append(f"{key.replace('__', '.')}={text}")
    return out


def interruptible() -> None:
    """``preexec_fn`` for a CLI process a test will Ctrl-C: start it with SIGINT's default
    disposition, as a terminal's foreground process has. A suite launched in the
    background (``cmd &`` in a script) ignores SIGINT, and its children inherit that, so
    the interrupt would never arrive."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def loop_asymptote_of(material):
    """M0 of a MaterialSI of the paper's loop (tagawa2003 or masing), N."""
    from warpcloth.kernels.bending_tagawa2003 import loop_asymptote

    b = material.bending
    return loop_asymptote(b.hysteresis_d1, b.hysteresis_alpha, b.hysteresis_k0)


def paper_loop(d1, alpha, k0, law="tagawa2003"):
    """The LawParameters of the paper's loop (SI)."""
    from warpcloth.strip import LawParameters

    return LawParameters.of(law, {"hysteresis_d1": d1, "hysteresis_alpha": alpha, "hysteresis_k0": k0})


def kes_cycle(k0: float = 2.5, step: float = 0.02):
    """The standard KES-FB2 path 0 → +K0 → −K0 → 0 (1/cm), sampled like the bundled example."""
    from warpcloth.calibrate.kes.kes_values import standard_cycle

    return standard_cycle(k0, step)


def kes_moment(material, k):
    """The kernel's moment (gf·cm/cm) of a [material] section's own law along a KES-unit path."""
    import numpy as np

    from warpcloth import units
    from warpcloth.scene import to_si
    from warpcloth.strip import moment_along_path

    m, _ = moment_along_path(to_si(material), np.asarray(k) * units.CURVATURE_PER_CM)
    return m / units.MOMENT_GF_CM_PER_CM


def run_cli(*args, cwd=None, timeout=None):
    """``warpcloth ARGS`` run in this process by the command's entry point
    (:func:`warpcloth.cli.app.main`) in ``cwd``, its output captured: a child process
    would spend ~2 s of CPU starting Python, Warp and pandas for each command. Returns a
    :class:`subprocess.CompletedProcess` like ``subprocess.run``. (``timeout`` is accepted
    for the same signature: a command here runs to its end.) What needs a process of its
    own (Ctrl-C, a kill, a file-size limit, two writers) starts one."""
    import contextlib
    import io
    import os
    import subprocess
    import warnings

    from warpcloth.cli.app import main

    out, err = io.StringIO(), io.StringIO()
    before = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with warnings.catch_warnings(), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main([str(a) for a in args])
            except SystemExit as exc:  # argparse's own errors and --help
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        os.chdir(before)
    return subprocess.CompletedProcess(list(args), code, out.getvalue(), err.getvalue())


SPACING_TRUTH = {
    "clamp.rotation_centre_dy_mm": 2.8,
    "damping.gamma_per_s": 0.4,
    "material.hysteresis_d1_gf_cm_per_cm": 0.05,
}
"""The parameters of the fine reference of the impulsive rotation (issue 22)."""


def rotation_scene_data(spacing_mm: float, duration_s: float = 0.25) -> dict:
    """Raw data of the bundled impulsive rotation under the masing law at ``spacing_mm``,
    dt in proportion (5e-6 s at the scene's 2.5 mm: converged, tests/test_convergence.py)."""
    from warpcloth.scene import read_scene_file, set_field

    data = read_scene_file("impulsive_rotation")
    for name, value in {
        "material.bending_law": "masing",
        "run.duration_s": duration_s,
        "strip.spacing_mm": spacing_mm,
        "integrator.dt_s": 5e-6 * spacing_mm / 2.5,
    }.items():
        set_field(data, name, value)
    return data


def fine_rotation_markers(spacing_mm: float = 1.25, noise_m: float = 1e-4, seed: int = 22, dt_factor: float = 1.0):
    """Markers every 10 mm on the impulsive rotation simulated at ``spacing_mm`` (masing, the
    :data:`SPACING_TRUTH`), 60 frames/s for 0.25 s, with seeded Gaussian noise of
    ``noise_m`` per coordinate: a measurement made by a converged fine simulation."""
    import numpy as np

    import warpcloth as wc
    from warpcloth.io.measured import TrackedShapes
    from warpcloth.scene import set_field

    data = rotation_scene_data(spacing_mm)
    for name, value in SPACING_TRUTH.items():
        set_field(data, name, value)
    set_field(data, "integrator.dt_s", data["integrator"]["dt_s"] * dt_factor)
    scene = wc.scene_from_dict(data)
    result = wc.simulate(scene)
    s = np.arange(0, 101, 10) * 1e-3
    node = scene.n_clamped - 1 + np.round(s / scene.spacing).astype(int)
    frames = len(result.frame_times)
    xy = result.frames[:, 0, node].reshape(-1, 2) + np.random.default_rng(seed).normal(0, noise_m, (frames * len(s), 2))
    return TrackedShapes(
        np.repeat(np.arange(frames), len(s)),
        np.repeat(result.frame_times, len(s)),
        np.tile(s, frames),
        xy[:, 0],
        xy[:, 1],
    )
