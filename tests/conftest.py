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
