"""Command line: ``warpcloth run | sweep | export-usd | plot | render | fit | clamp | material``
(``--help`` on each); one module per command group, registered in :mod:`.app`.

Importing this package is cheap (``warpcloth`` loads its names lazily): :func:`main`
catches a Ctrl-C while the heavy modules (Warp, NumPy, pandas) are imported, so an
interrupt at any moment of start-up is exit 130 with one line, never a traceback.
"""

from __future__ import annotations

from collections.abc import Sequence

from .interrupt import EXIT_INTERRUPTED, EXIT_UNUSABLE_INPUT, interrupted_at_start


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``warpcloth`` command; returns the exit status."""
    import sys

    try:
        from .app import main as run_command
    except KeyboardInterrupt:
        return interrupted_at_start()
    except ImportError as exc:
        from warpcloth.kernels.law import LawRegistryError

        if not isinstance(exc, LawRegistryError):
            raise
        print(f"warpcloth: {exc}", file=sys.stderr)  # a broken law of an installed package
        return EXIT_UNUSABLE_INPUT
    return run_command(argv)


__all__ = ["EXIT_INTERRUPTED", "interrupted_at_start", "main"]
