"""Shared helpers: every test runs on the CPU device (CI has no GPU)."""

import logging
import signal

import warp as wp

wp.config.log_level = logging.WARNING


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


def kes_cycle(k0: float = 2.5, step: float = 0.02):
    """The standard KES-FB2 path 0 → +K0 → −K0 → 0 (1/cm), sampled like the bundled example."""
    from warpcloth.calibrate.kes.kes_values import standard_cycle

    return standard_cycle(k0, step)


def kes_moment(material, k):
    """The kernel's moment (gf·cm/cm) of a [material] section's own law along a KES-unit path."""
    import numpy as np

    from warpcloth import units
    from warpcloth.scene import to_si
    from warpcloth.sim import moment_along_path

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
