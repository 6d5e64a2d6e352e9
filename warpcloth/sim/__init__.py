"""The strip's package under its former name: ``warpcloth.sim`` is :mod:`warpcloth.strip`
(the strip and the sheet are sibling bodies on :mod:`warpcloth.core` since issue 37).
Scripts that import from here keep working; new code imports :mod:`warpcloth.strip`."""

from warpcloth.strip import *  # noqa: F403
from warpcloth.strip import __all__  # noqa: F401
