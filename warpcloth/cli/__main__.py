"""``python -m warpcloth.cli``."""

import sys

from . import main

sys.exit(main())
