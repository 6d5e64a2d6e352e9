"""``python -m warpcloth.cli``."""

from . import program

program()
