"""Option types shared by the command groups: checked when the command line is parsed,
before anything runs."""

from __future__ import annotations

import argparse

import warp as wp


def device(value: str) -> str:
    """``--device``: a Warp device of this machine (checked before anything runs)."""
    try:
        wp.get_device(value)
    except (RuntimeError, ValueError) as exc:
        known = ", ".join(d.alias for d in wp.get_devices())
        raise argparse.ArgumentTypeError(f"{value!r} is not a device of this machine ({exc}); it has: {known}") \
            from None
    return value
