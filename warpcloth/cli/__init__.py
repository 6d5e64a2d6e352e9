"""Command line: ``warpcloth run | sweep | export-usd | plot | render | fit | clamp | material``
(``--help`` on each); one module per command group, registered in :mod:`.app`."""

from .app import main

__all__ = ["main"]
