"""How the command line reports what stops it before a command starts its work — a
Ctrl-C, or a broken law of an installed package — (shared by :func:`warpcloth.cli.main`
and :mod:`.app`, so neither imports the other back)."""

from __future__ import annotations

import sys

EXIT_INTERRUPTED = 130  # the shell's convention for SIGINT
EXIT_UNUSABLE_INPUT = 2  # bad input of any kind: a scene, a data file, an option, a law's description


def interrupted_at_start() -> int:
    """Report a Ctrl-C that came before the command started its work; returns 130."""
    print("warpcloth: interrupted while starting, before anything was written", file=sys.stderr)
    return EXIT_INTERRUPTED
