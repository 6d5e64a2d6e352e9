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
    except Exception as exc:
        if _interrupted(exc):
            return interrupted_at_start()
        from warpcloth.kernels.law import LawRegistryError

        if not isinstance(exc, LawRegistryError):
            raise
        print(f"warpcloth: {exc}", file=sys.stderr)  # a broken law of an installed package
        return EXIT_UNUSABLE_INPUT
    return run_command(argv)


def _interrupted(exc: BaseException) -> bool:
    # A Ctrl-C that lands in a class body's ``__set_name__`` (a dataclass field, while a
    # module is imported) reaches here as the RuntimeError Python 3.11 wraps it in
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def program() -> None:
    """The program ``warpcloth`` (its console script and ``python -m warpcloth.cli``): exit
    with :func:`main`'s status. An interrupted command exits at once, its output flushed:
    CPython ends a program by SIGINT (status −2, not 130) when a KeyboardInterrupt ever
    passed through code a C extension ran with ``PyRun_*``, as during the imports at start
    (tests/test_faults.py saw it about once in 20 under load), even one warpcloth caught and
    reported; what an interrupted command wrote is committed before main returns."""
    import os
    import sys

    status = main()
    if status == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    sys.exit(status)


__all__ = ["EXIT_INTERRUPTED", "interrupted_at_start", "main", "program"]
