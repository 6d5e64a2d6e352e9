"""How the command line reports a Ctrl-C that came before a command started its work
(shared by :func:`warpcloth.cli.main` and :mod:`.app`, so neither imports the other back)."""

from __future__ import annotations

import sys

EXIT_INTERRUPTED = 130  # the shell's convention for SIGINT


def interrupted_at_start() -> int:
    """Report a Ctrl-C that came before the command started its work; returns 130."""
    print("warpcloth: interrupted while starting, before anything was written", file=sys.stderr)
    return EXIT_INTERRUPTED
