"""Shared helpers: every test runs on the CPU device (CI has no GPU)."""

import logging

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
